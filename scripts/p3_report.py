#!/usr/bin/python3
"""Compares a P3 run (implicit_sim_run's trajectory.csv) with the reference solution and writes a picture.

Usage: p3_report.py RUN_DIR REFERENCE_CSV
Prints the contact events and the velocity at t = 3.5 s next to the reference, and writes RUN_DIR/p3_report.svg
(velocity components and normal forces over time, ours as lines, the reference as dots). Plain Python 3, no
third-party modules."""
import csv
import json
import math
import os
import sys

REF_EVENTS = {"A separates": 3.2132058167499182, "B separates": 3.7016004163001717, "B rolls -> slides": 2.944806757736996}
REF_V35 = (4.852055739686922, 0.14948342010862542, -4.083242953676649)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {key: [float(r[key]) for r in rows] for key in rows[0]}


def first_time(t, condition):
    return next((ti for ti, c in zip(t, condition) if c), float("nan"))


def events(run):
    t = run["t"][1:]
    fa, fb, slip_b = run["ball-sphere_a.fn"][1:], run["ball-sphere_b.fn"][1:], run["ball-sphere_b.slip"][1:]
    return {
        "A separates": first_time(t, [f <= 1e-9 for f in fa]),
        "B separates": first_time(t, [f <= 1e-9 for f in fb]),
        "B rolls -> slides": first_time(t, [f > 1e-9 and s > 1e-4 for f, s in zip(fb, slip_b)]),
    }


def svg_panel(x0, y0, w, h, title, series, t_max, y_label):
    """One panel: series = [(label, color, xs, ys, dotted)]."""
    ys_all = [y for _, _, _, ys, _ in series for y in ys if math.isfinite(y)]
    lo, hi = min(ys_all), max(ys_all)
    if hi - lo < 1e-12:
        hi = lo + 1.0
    pad = 0.05 * (hi - lo)
    lo, hi = lo - pad, hi + pad
    sx = lambda t: x0 + w * t / t_max
    sy = lambda y: y0 + h - h * (y - lo) / (hi - lo)
    out = [f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="white" stroke="#888"/>',
           f'<text x="{x0 + w / 2}" y="{y0 - 8}" text-anchor="middle" font-size="14">{title}</text>',
           f'<text x="{x0 - 45}" y="{y0 + h / 2}" font-size="12" transform="rotate(-90 {x0 - 45} {y0 + h / 2})" '
           f'text-anchor="middle">{y_label}</text>']
    for k in range(6):
        t = t_max * k / 5
        out.append(f'<text x="{sx(t)}" y="{y0 + h + 15}" font-size="11" text-anchor="middle">{t:.1f}</text>')
        y = lo + (hi - lo) * k / 5
        out.append(f'<text x="{x0 - 5}" y="{sy(y) + 4}" font-size="11" text-anchor="end">{y:.2f}</text>')
    out.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 30}" font-size="12" text-anchor="middle">t (s)</text>')
    for i, (label, color, xs, ys, dotted) in enumerate(series):
        pts = [(sx(x), sy(y)) for x, y in zip(xs, ys) if math.isfinite(y)]
        if dotted:
            out += [f'<circle cx="{px:.1f}" cy="{py:.1f}" r="1.6" fill="{color}"/>' for px, py in pts[::5]]
        else:
            path = " ".join(f"{px:.1f},{py:.1f}" for px, py in pts)
            out.append(f'<polyline points="{path}" fill="none" stroke="{color}" stroke-width="1.5"/>')
        if label:
            out.append(f'<text x="{x0 + w - 10}" y="{y0 + 16 + 14 * i}" font-size="11" fill="{color}" '
                       f'text-anchor="end">{label}</text>')
    return out


def main(run_dir, reference_csv):
    run = read_csv(os.path.join(run_dir, "trajectory.csv"))
    ref = read_csv(reference_csv)
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    ours = events(run)
    print("P3 sphere on two spheres: implicit_sim against the high-accuracy reference")
    print(f"{'event':<20}{'implicit_sim (s)':>18}{'reference (s)':>16}{'difference (s)':>16}")
    for name, t_ref in REF_EVENTS.items():
        print(f"{name:<20}{ours[name]:>18.3f}{t_ref:>16.4f}{ours[name] - t_ref:>16.4f}")
    i35 = min(range(len(run["t"])), key=lambda i: abs(run["t"][i] - 3.5))
    v = (run["ball.vx"][i35], run["ball.vy"][i35], run["ball.vz"][i35])
    err = math.dist(v, REF_V35) / math.hypot(*REF_V35)
    print(f"v(3.5 s) = ({v[0]:.4f}, {v[1]:.4f}, {v[2]:.4f}) m/s, reference ({REF_V35[0]:.4f}, {REF_V35[1]:.4f}, "
          f"{REF_V35[2]:.4f}): relative error {100 * err:.2f} %")
    print(f"max penetration {summary['max_penetration']:.2e} m, non-converged steps {summary['nonconverged_steps']}, "
          f"{summary['us_per_step']:.0f} us/step over {summary['steps']} steps")
    t_max = max(run["t"])
    colors = ["#d62728", "#2ca02c", "#1f77b4"]
    parts = ['<svg xmlns="http://www.w3.org/2000/svg" width="900" height="720" font-family="sans-serif">',
             '<rect width="900" height="720" fill="#f8f8f8"/>']
    series = []
    for c, (key, rkey) in zip(colors, [("ball.vx", "vx"), ("ball.vy", "vy"), ("ball.vz", "vz")]):
        series.append((key + " (line: implicit_sim, dots: reference)", c, run["t"], run[key], False))
        series.append(("", c, ref["t"], ref[rkey], True))
    parts += svg_panel(90, 40, 780, 280, "P3: velocity of the small sphere", series, t_max, "m/s")
    series = []
    for c, (key, rkey) in zip(colors, [("ball-sphere_a.fn", "A_lambda_n"), ("ball-sphere_b.fn", "B_lambda_n")]):
        series.append((key + " (line: implicit_sim, dots: reference)", c, run["t"][1:], run[key][1:], False))
        series.append(("", c, ref["t"], ref[rkey], True))
    parts += svg_panel(90, 390, 780, 280, "P3: normal force at contacts A and B", series, t_max, "N")
    parts.append("</svg>")
    out = os.path.join(run_dir, "p3_report.svg")
    with open(out, "w") as f:
        f.write("\n".join(parts))
    print(f"picture: {out}")
    return out


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
