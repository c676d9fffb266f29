#!/usr/bin/python3
"""Regenerates the paper's figures from our own runs, next to the exact or reference solutions, and checks them.

Usage: paper_figures.py OUTDIR --runner PATH [--quick]
Runs the headless runner on the paper's scenes with the paper's step (--scheme paper), and with the second-order
RATTLE step too where the two differ (Fig. 1(a), Fig. 6, the ellipsoid on an ellipsoid), and writes into OUTDIR:
  fig1a_p1_energy_ngons.png    P1: kinetic energy of the smooth disc and of N-gon discs (N = 10 ... 1000), h = 0.01
  fig1b_p1_energy_1000gon.png  P1: the 1000-gon at h = 0.01, 0.005, 0.001, 0.0005 and the smooth disc
  fig3_p2_velocities.png       P2: spin and the other velocity components (h = 0.07) with the exact solution
  fig4_p2_friction.png         P2: torsional moment and tangential friction (h = 0.07) with the exact solution
  fig6_p3_velocities.png       P3: velocity and angular velocity with the reference
  fig7_p3_contact_a.png, fig8_p3_contact_b.png   P3 per contact: normal force, mu * normal force, friction
                               magnitude and slip speed with the reference
  ellipsoid_on_ellipsoid.png   an ellipsoid toppling down a fixed ellipsoid (no closed-form distance): gap, energy
Prints, per figure, the numbers it shows against the reference with PASS/FAIL, and exits 1 if a check fails.
P1 runs 5 s (about 4 min, most of it the 1000-gon at h = 0.0005); --quick shortens Fig. 1(a) to 1 s and Fig. 1(b) to
0.1 s (about 40 s in all) for tests."""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REFERENCE = os.path.join(REPO, "test", "data", "reference")
FAILURES = []


def check(name, value, expected, ok):
    status = "PASS" if ok else "FAIL"
    if not ok:
        FAILURES.append(name)
    print(f"  [{status}] {name}: {value} (expected {expected})")


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {key: [float(r[key]) for r in rows] for key in rows[0]}


def run(runner, scene, duration, h, work, scheme="paper"):
    """One run with the paper's step, or with the second-order RATTLE step (scheme "rattle")."""
    out = os.path.join(work, f"{os.path.splitext(scene)[0]}_h{h:g}_T{duration:g}_{scheme}")
    status = subprocess.run([runner, "--scene", os.path.join(REPO, "scenes", scene), "--duration", str(duration),
                             "--dt", str(h), "--scheme", scheme, "--out", out], stdout=subprocess.DEVNULL).returncode
    if status not in (0, 1):  # 1: a step did not converge, which the figure's checks report
        raise RuntimeError(f"{runner} exited with {status} on {scene}")
    with open(os.path.join(out, "summary.json")) as f:
        return read_csv(os.path.join(out, "trajectory.csv")), json.load(f)


def finish(axes, legend=True):
    for axis in axes:
        axis.grid(True, alpha=0.3)
        if legend:
            axis.legend(fontsize=8)


def save(fig, out_dir, name):
    fig.tight_layout()
    path = os.path.join(out_dir, name)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")


def figure_1(runner, out_dir, work, quick):
    T = 1.0 if quick else 5.0
    print("Fig. 1(a): P1 kinetic energy, smooth disc and N-gons, h = 0.01")
    fig, axis = plt.subplots(figsize=(8, 4.5))
    ratios, rattle_ratios = {}, {}
    for label, scene in [("smooth", "p1_disc_rolling.urdf")] + [(f"{n}-gon", f"p1_ngon{n}.urdf")
                                                                 for n in (10, 20, 40, 100, 1000)]:
        run_, _ = run(runner, scene, T, 0.01, work)
        ke = run_["energy.kinetic"]
        ratios[label] = ke[-1] / ke[0]
        line, = axis.plot(run_["t"], ke, label=f"{label}: KE(T)/KE0 = {ratios[label]:.4f}")
        rattle, _ = run(runner, scene, T, 0.01, work, "rattle")
        rattle_ratios[label] = rattle["energy.kinetic"][-1] / rattle["energy.kinetic"][0]
        axis.plot(rattle["t"], rattle["energy.kinetic"], ":", color=line.get_color(),
                  label=f"{label}, RATTLE: {rattle_ratios[label]:.4f}")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("kinetic energy (J)")
    axis.set_title(f"P1 rolling disc, h = 0.01 s: the smooth disc keeps its energy; the paper's step as lines, RATTLE "
                   "dotted", fontsize=9)
    finish([axis])
    save(fig, out_dir, "fig1a_p1_energy_ngons.png")
    check("smooth disc |KE(T)/KE0 - 1|", f"{abs(ratios['smooth'] - 1):.1e}", "< 1e-9", abs(ratios["smooth"] - 1) < 1e-9)
    order = [ratios[f"{n}-gon"] for n in (10, 20, 40, 100, 1000)]
    check("N-gon KE(T)/KE0 for N = 10, 20, 40, 100, 1000", ", ".join(f"{r:.4f}" for r in order),
          "increasing with N towards the smooth disc's 1",
          all(a < b for a, b in zip(order, order[1:])) and order[-1] <= ratios["smooth"] + 1e-3)
    order = [rattle_ratios[f"{n}-gon"] for n in (10, 20, 40, 100, 1000)]
    check("RATTLE: smooth disc |KE(T)/KE0 - 1|; N-gon KE(T)/KE0 for N = 10 ... 1000",
          f"{abs(rattle_ratios['smooth'] - 1):.1e}; " + ", ".join(f"{r:.4f}" for r in order),
          "< 1e-9; increasing with N towards the smooth disc's 1",
          abs(rattle_ratios["smooth"] - 1) < 1e-9 and all(a < b for a, b in zip(order, order[1:])) and
          order[-1] <= rattle_ratios["smooth"] + 1e-3)

    print("Fig. 1(b): the 1000-gon at four time steps and the smooth disc")
    T = 0.1 if quick else 5.0
    fig, axis = plt.subplots(figsize=(8, 4.5))
    smooth, _ = run(runner, "p1_disc_rolling.urdf", T, 0.01, work)
    axis.plot(smooth["t"], smooth["energy.kinetic"], "k", label="smooth disc, h = 0.01")
    smooth_error = abs(smooth["energy.kinetic"][-1] / smooth["energy.kinetic"][0] - 1)
    limit = vertex_impact_limit(1000, T)
    ratios, worst_penetration, nonconverged = [], 0.0, 0
    for h in (0.01, 0.005, 0.001, 0.0005):
        run_, summary = run(runner, "p1_ngon1000.urdf", T, h, work)
        ke = run_["energy.kinetic"]
        ratios.append(ke[-1] / ke[0])
        worst_penetration = max(worst_penetration, summary["max_penetration"])
        nonconverged += summary["nonconverged_steps"]
        axis.plot(run_["t"], ke, label=f"1000-gon, h = {h:g}: KE(T)/KE0 = {ratios[-1]:.5f}")
    times = [T * i / 100 for i in range(101)]
    axis.plot(times, [6.75 * vertex_impact_limit(1000, ti) for ti in times], color="gray", ls=":",
              label=f"1000-gon as h -> 0 (inelastic vertex impacts): {limit:.5f}")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("kinetic energy (J)")
    axis.set_title(f"P1: 1000-gon disc at four time steps, smooth disc at h = 0.01 ({T:g} s)")
    finish([axis])
    save(fig, out_dir, "fig1b_p1_energy_1000gon.png")
    check("1000-gon KE(T)/KE0 for h = 0.01, 0.005, 0.001, 0.0005", ", ".join(f"{r:.5f}" for r in ratios),
          f"each further from 1 than the smooth disc ({smooth_error:.1e})",
          all(abs(r - 1) > 10 * smooth_error for r in ratios))
    check("1000-gon at h = 0.0005: KE(T)/KE0", f"{ratios[-1]:.5f}",
          f"between the vertex-impact limit {limit:.5f} and 1", limit <= ratios[-1] <= 1)
    check("1000-gon runs: non-converged steps, largest penetration (m)", f"{nonconverged}, {worst_penetration:.1e}",
          "0, < 1e-9", nonconverged == 0 and worst_penetration < 1e-9)


def vertex_impact_limit(sides, duration):
    """KE(T)/KE0 of a uniform regular polygon (circumradius 1 m, I = m r^2 / 2) rolling at 3 m/s when every vertex
    landing is an inelastic impact that keeps the angular momentum about the new vertex: the true polygon's loss."""
    angle = 2 * math.pi / sides
    per_impact = ((0.5 + math.cos(angle)) / 1.5) ** 2
    impacts = 3.0 * duration / (2 * math.sin(math.pi / sides))
    return per_impact ** impacts


def figure_3_4(runner, out_dir, work):
    print("Figs. 3 and 4: P2 spinning sphere, h = 0.07, with the exact solution")
    run_, _ = run(runner, "p2_sphere_spinning.urdf", 1.4, 0.07, work)
    exact = read_csv(os.path.join(REFERENCE, "P2.csv"))
    t = run_["t"]
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    axes[0].plot(exact["t"], exact["omega_z"], "k-", label="exact")
    axes[0].plot(t, run_["ball.wz"], "o", ms=4, label="implicit_sim, h = 0.07")
    axes[0].set_ylabel("spin w_z (rad/s)")
    for c in ("vx", "vy", "vz", "wx", "wy"):
        axes[1].plot(t, run_[f"ball.{c}"], label=c)
    axes[1].set_ylabel("other velocities (m/s, rad/s)")
    axes[1].set_xlabel("t (s)")
    finish(axes)
    axes[0].set_title("P2 (paper Fig. 3): the spin decays linearly and stops; nothing else moves")
    save(fig, out_dir, "fig3_p2_velocities.png")
    slope = (run_["ball.wz"][10] - run_["ball.wz"][0]) / (t[10] - t[0])
    stop = next(ti for ti, w in zip(t, run_["ball.wz"]) if abs(w) < 1e-9)
    check("spin slope over 0-0.7 s (rad/s^2)", f"{slope:.6f}", "-1.962000", abs(slope + 1.962) < 1e-6)
    check("first step time with zero spin (s)", f"{stop:.2f}", "1.05 (exact stop 1.00 s, h = 0.07)", abs(stop - 1.05) < 1e-9)
    others = max(abs(v) for c in ("vx", "vy", "vz", "wx", "wy") for v in run_[f"ball.{c}"])
    check("largest other velocity", f"{others:.1e}", "< 1e-8", others < 1e-8)

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    axes[0].plot(exact["t"], [abs(m) for m in exact["m_torsion"]], "k-", label="exact |torsional moment|")
    axes[0].plot(t[1:], [abs(m) for m in run_["ball-ground.mr"][1:]], "o", ms=4, label="implicit_sim")
    axes[0].set_ylabel("torsional moment (N m)")
    axes[1].plot(exact["t"], exact["f_t"], "k-", label="exact")
    axes[1].plot(t[1:], run_["ball-ground.ft"][1:], "o", ms=4, label="implicit_sim")
    axes[1].set_ylabel("tangential friction (N)")
    axes[1].set_xlabel("t (s)")
    finish(axes)
    axes[0].set_title("P2 (paper Fig. 4): torsional friction mu e_r m g while spinning, then 0")
    save(fig, out_dir, "fig4_p2_friction.png")
    moment = abs(run_["ball-ground.mr"][1])
    check("torsional moment while spinning (N m)", f"{moment:.5f}", "0.78480", abs(moment - 0.7848) < 1e-6)


def figure_6_7_8(runner, out_dir, work):
    print("Figs. 6, 7 and 8: P3 sphere on two spheres, h = 0.01, with the reference")
    run_, summary = run(runner, "p3_sphere_on_two_spheres.urdf", 5.0, 0.01, work)
    rattle, _ = run(runner, "p3_sphere_on_two_spheres.urdf", 5.0, 0.01, work, "rattle")
    ref = read_csv(os.path.join(REFERENCE, "P3_reference.csv"))
    t = run_["t"]
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for axis, kind, unit in ((axes[0], "v", "m/s"), (axes[1], "w", "rad/s")):
        for c in "xyz":
            line, = axis.plot(t, run_[f"ball.{kind}{c}"], label=f"{kind}_{c}")
            axis.plot(rattle["t"], rattle[f"ball.{kind}{c}"], ":", color=line.get_color())
            axis.plot(ref["t"][::10], ref[f"{kind}{c}"][::10], "o", ms=3, color=line.get_color())
        axis.set_ylabel(f"{'velocity' if kind == 'v' else 'angular velocity'} ({unit})")
    finish(axes)
    axes[1].set_xlabel("t (s)")
    axes[0].set_title("P3 (paper Fig. 6): the paper's step as lines, RATTLE dotted, the reference as dots")
    save(fig, out_dir, "fig6_p3_velocities.png")
    j35 = min(range(len(ref["t"])), key=lambda i: abs(ref["t"][i] - 3.5))
    theirs = [ref[f"v{c}"][j35] for c in "xyz"]
    for name, r, bar in (("the paper's step", run_, 0.03), ("RATTLE", rattle, 0.01)):
        i35 = min(range(len(r["t"])), key=lambda i: abs(r["t"][i] - 3.5))
        ours = [r[f"ball.v{c}"][i35] for c in "xyz"]
        error = sum((a - b) ** 2 for a, b in zip(ours, theirs)) ** 0.5 / sum(b * b for b in theirs) ** 0.5
        check(f"velocity at t = 3.5 s, relative error ({name})", f"{100 * error:.2f} %", f"< {100 * bar:g} %",
              error < bar)
    mu = {p["name"]: p["mu"] for p in summary["pairs"]}
    events = {}
    for figure, contact, pair in (("fig7_p3_contact_a.png", "A", "ball-sphere_a"),
                                  ("fig8_p3_contact_b.png", "B", "ball-sphere_b")):
        fn, ft, slip = run_[f"{pair}.fn"][1:], run_[f"{pair}.ft"][1:], run_[f"{pair}.slip"][1:]
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        axes[0].plot(t[1:], fn, label="normal force")
        axes[0].plot(t[1:], [mu[pair] * f for f in fn], "--", label="mu * normal force")
        axes[0].plot(t[1:], ft, label="friction magnitude")
        axes[0].plot(ref["t"][::10], ref[f"{contact}_lambda_n"][::10], "o", ms=3, color="tab:blue",
                     label="reference normal force")
        axes[0].plot(ref["t"][::10], ref[f"{contact}_friction"][::10], "o", ms=3, color="tab:green",
                     label="reference friction")
        axes[0].set_ylabel("force (N)")
        axes[1].plot(t[1:], slip, label="slip speed")
        axes[1].plot(ref["t"][::10], ref[f"{contact}_slip_speed"][::10], "o", ms=3, label="reference")
        axes[1].set_ylabel("slip speed (m/s)")
        axes[1].set_xlabel("t (s)")
        finish(axes)
        axes[0].set_title(f"P3 (paper Fig. {7 if contact == 'A' else 8}): contact {contact}")
        save(fig, out_dir, figure)
        events[f"{contact} separates"] = next((ti for ti, f in zip(t[1:], fn) if f <= 0.0), float("nan"))
        if contact == "B":  # the reference's roll -> slide time is 2.9448 s; its slip exceeds 1e-4 m/s at 2.9558 s
            events["B slip > 1e-4 m/s"] = next((ti for ti, s in zip(t[1:], slip) if s > 1e-4), float("nan"))
    with open(os.path.join(REFERENCE, "summary.json")) as f:
        names = {"separate": "{} separates", "slip_B>0.0001": "{} slip > 1e-4 m/s"}
        reference_events = {names[kind].format(c): time for kind, c, time in json.load(f)["P3"]["events"]
                            if kind in names}
    for name, time in sorted(events.items()):
        check(f"P3 event '{name}' (s)", f"{time:.2f}", f"{reference_events[name]:.4f} +- 0.02",
              abs(time - reference_events[name]) < 0.02)


def ellipsoid_on_ellipsoid(runner, out_dir, work):
    print("Ellipsoid on a fixed ellipsoid (no closed-form distance), h = 0.005 and 0.0025")
    runs = {h: run(runner, "ellipsoid_on_ellipsoid.urdf", 1.8, h, work) for h in (0.005, 0.0025)}
    rattle = {h: run(runner, "ellipsoid_on_ellipsoid.urdf", 1.8, h, work, "rattle") for h in (0.005, 0.0025)}
    run_, summary = runs[0.005]
    t = run_["t"]
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    axes[0].plot(t, run_["egg-mound.gap"], "k")
    axes[0].set_ylabel("gap (m)")
    axes[1].plot(t[1:], run_["egg-mound.fn"][1:], label="normal force")
    axes[1].plot(t[1:], run_["egg-mound.ft"][1:], label="friction magnitude")
    axes[1].set_ylabel("force (N)")
    axes[2].plot(t, run_["energy.kinetic"], label="kinetic, h = 0.005")
    rises, rattle_rises = {}, {}
    for name, scheme_runs, rise in (("paper", runs, rises), ("RATTLE", rattle, rattle_rises)):
        for h, (r, _) in scheme_runs.items():
            total = [k + p for k, p in zip(r["energy.kinetic"], r["energy.potential"])]
            axes[2].plot(r["t"], [e - total[0] for e in total], "-" if name == "paper" else ":",
                         label=f"total - initial, h = {h:g} ({name})")
            rise[h] = (max(total) - total[0], max(e - min(total[:i + 1]) for i, e in enumerate(total)))
    axes[2].set_ylabel("energy (J)")
    axes[2].set_xlabel("t (s)")
    finish(axes[1:])
    finish(axes[:1], legend=False)
    axes[0].set_title("An ellipsoid toppling and rolling down a fixed ellipsoid, then leaving it")
    save(fig, out_dir, "ellipsoid_on_ellipsoid.png")
    penetration = max(s["max_penetration"] for _, s in list(runs.values()) + list(rattle.values()))
    nonconverged = sum(s["nonconverged_steps"] for _, s in list(runs.values()) + list(rattle.values()))
    check("largest penetration (m), non-converged steps", f"{penetration:.1e}, {nonconverged}", "< 1e-9, 0",
          penetration < 1e-9 and nonconverged == 0)
    check("total energy above the initial (J)", f"{max(rises[0.005][0], rises[0.0025][0]):.1e}",
          "<= 1e-9 (the contact dissipates)", max(rises[0.005][0], rises[0.0025][0]) <= 1e-9)
    # Rolling over a curved surface with p1 = p0 + h v1 lets the normal impulse do O(h) work per unit time (the
    # end-of-step chord points out of the convex mound), so the largest local rise of the total energy must halve
    # with h: it is a discretization error, not a modelling one.
    ratio = rises[0.0025][1] / rises[0.005][1]
    check("largest local total-energy rise at h = 0.005 and 0.0025 (J), ratio",
          f"{rises[0.005][1]:.2e}, {rises[0.0025][1]:.2e}, {ratio:.2f}", "ratio 0.5 +- 0.2 (first order in h)",
          abs(ratio - 0.5) <= 0.2)
    # The RATTLE step: the same rise is a second-order error (it quarters with h).
    ratio = rattle_rises[0.0025][1] / rattle_rises[0.005][1]
    check("RATTLE: largest local total-energy rise at h = 0.005 and 0.0025 (J), ratio",
          f"{rattle_rises[0.005][1]:.2e}, {rattle_rises[0.0025][1]:.2e}, {ratio:.2f}",
          "ratio 0.25 +- 0.1 (second order in h)", abs(ratio - 0.25) <= 0.1)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir")
    parser.add_argument("--runner", required=True, help="path of implicit_sim_run")
    parser.add_argument("--quick", action="store_true", help="short horizons (tests)")
    args = parser.parse_args(argv)
    out_dir = os.path.abspath(args.out_dir)
    work = os.path.join(out_dir, "runs")
    os.makedirs(work, exist_ok=True)
    figure_1(args.runner, out_dir, work, args.quick)
    figure_3_4(args.runner, out_dir, work)
    figure_6_7_8(args.runner, out_dir, work)
    ellipsoid_on_ellipsoid(args.runner, out_dir, work)
    print(f"checks: {'all passed' if not FAILURES else 'FAILED: ' + '; '.join(FAILURES)}")
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
