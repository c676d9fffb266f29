#!/usr/bin/python3
"""Monte Carlo drop of a part with unequal faces: which face does it come to rest on?

What it shows: building a scene in Python (a rounded box, the superellipsoid |x/a|^p + |y/b|^p + |z/c|^p <= 1 with
three different half extents a > b > c, on the plane z = 0), setting a random initial state through `state.q` and
`state.v` (an orientation uniform on SO(3) as a unit quaternion, a random spin), stepping each drop until the part is at
rest, classifying its resting face, and keeping the solver honest. Only drops at rest whose every step converged count
in the histogram; the others are reported and counted on their own: a drop with a non-converged step
(`not_converged`), one whose mechanical energy (kinetic plus gravitational) rose above its value at release by more
than --energy-rise-tolerance (`energy_rise`: a passive part dropped on a plane can only lose energy), and one that did
not come to rest within --max-time (`not_at_rest`).

Each drop: the part's lowest point starts --height above the ground (its centre is placed from the support function
of the shape in the drawn orientation), with zero linear velocity and an angular velocity of uniform direction and a
magnitude uniform in [0, --spin-max]. It is stepped until its kinetic energy stayed below --rest-energy for --rest-hold
of simulated time, or --max-time. The resting face is the body axis (+x, -x, +y, -y, +z, -z) that points most nearly
down; the tilt is the angle between that axis and the downward vertical. Drop i draws from its own generator seeded
with (--seed, i), so the first N drops of a larger run are the drops of a run with --samples N.

The time-stepping scheme defaults to the paper's first-order step: its numerical damping stands in for a real part's
material damping; every drop of the default run comes to rest and none gains energy. With --scheme rattle every drop
comes to rest too and none gains energy, at about 3 times the wall time (examples/README.md).

Run (after `source /tmp/implicit_sim_ws/devel/setup.bash`, from the repository root):
    /usr/bin/python3 examples/monte_carlo_drop.py                       # 1000 drops, seed 1
    /usr/bin/python3 examples/monte_carlo_drop.py --samples 20          # a quick look
    /usr/bin/python3 examples/monte_carlo_drop.py --half-extents 0.05 0.05 0.05 --samples 300 --out /tmp/cube

Writes into --out (default examples_output/monte_carlo_drop/):
    drops.csv          one row per drop: its draws, outcome (rest, not_converged, energy_rise, not_at_rest), face,
                       tilt, the error of the centre's height at rest, time to rest, steps, non-converged steps,
                       Newton iterations, the largest rise of its mechanical energy (J) above its value at release
    summary.json       the parameters, face counts (drops at rest with every step converged), the other outcomes
    faces.png          histogram of the resting faces, and of the time to rest
    part_drop.urdf     the scene that was simulated
and prints the face table. Exit status 0, or 1 when no drop could be counted.
"""
import argparse
import csv
import json
import math
import pathlib
import sys
import time

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import implicit_sim  # noqa: E402
from implicit_sim.scene import Scene, Shape  # noqa: E402

FACES = ("+x", "-x", "+y", "-y", "+z", "-z")
PART = "part"


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=1000, help="number of drops (default 1000)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random draws (default 1)")
    parser.add_argument("--half-extents", type=float, nargs=3, default=(0.05, 0.035, 0.025), metavar=("A", "B", "C"),
                        help="half extents of the rounded box along its x, y, z, m (default 0.05 0.035 0.025)")
    parser.add_argument("--exponent", type=float, default=10.0,
                        help="superellipsoid exponent p in [2, 100]: larger is a sharper box (default 10)")
    parser.add_argument("--mass", type=float, default=0.5, help="kg (default 0.5)")
    parser.add_argument("--mu", type=float, default=0.5, help="friction coefficient with the ground (default 0.5)")
    parser.add_argument("--e-roll", type=float, default=0.0,
                        help="rolling resistance with the ground, m (default 0: none)")
    parser.add_argument("--height", type=float, default=0.1,
                        help="height of the part's lowest point at release, m (default 0.1)")
    parser.add_argument("--spin-max", type=float, default=5.0,
                        help="largest initial angular speed, rad/s (default 5)")
    parser.add_argument("--h", type=float, default=0.005, help="time step, s (default 0.005)")
    parser.add_argument("--scheme", choices=("rattle", "paper"), default="paper",
                        help="time-stepping scheme (default paper: see the docstring)")
    parser.add_argument("--newton-max-iterations", type=int, default=None,
                        help="the solver's iteration cap (default: the simulator's, 100); a small cap such as 2 shows "
                             "how non-converged drops are reported and left out")
    parser.add_argument("--rest-energy", type=float, default=1e-5,
                        help="at rest: kinetic energy below this, J (default 1e-5) ...")
    parser.add_argument("--rest-hold", type=float, default=0.2, help="... for this long, s (default 0.2)")
    parser.add_argument("--max-time", type=float, default=5.0, help="longest simulated time per drop, s (default 5)")
    parser.add_argument("--energy-rise-tolerance", type=float, default=1e-6,
                        help="a drop whose mechanical energy rose above its value at release by more than this (J) is "
                             "not counted (default 1e-6: round-off is about 1e-15 J)")
    parser.add_argument("--out", default="examples_output/monte_carlo_drop", help="output directory")
    arguments = parser.parse_args(argv)
    if arguments.samples < 1:
        parser.error("--samples must be at least 1")
    if min(arguments.half_extents) <= 0 or arguments.height < 0:
        parser.error("--half-extents must be > 0 and --height >= 0")
    if not 0 <= arguments.e_roll <= 1000:
        parser.error(f"--e-roll must be in [0, 1000] m, got {arguments.e_roll}")
    return arguments


def part_scene(half_extents, exponent, mass, mu, e_roll=0.0):
    """URDF text: the rounded box `part` on a floating joint above the ground plane z = 0 (doc/scenes.md)."""
    a, b, c = half_extents
    scene = Scene("part_drop", comment=f"examples/monte_carlo_drop.py: a rounded box (superellipsoid, half extents {a} "
                  f"{b} {c} m, exponent {exponent},\n     {mass} kg, inertia of the uniform solid) dropped on the "
                  f"ground plane z = 0; mu = {mu}, e_t = e_o = 1,\n     e_r = 0.01 m. The script sets the part's initial pose "
                  "and twist per drop.")
    scene.friction(mu=mu, e_t=1, e_o=1, e_r=0.01, **({"e_roll": e_roll} if e_roll > 0 else {}))
    scene.halfspace("ground")
    scene.link(PART, mass, visual=Shape.box((2 * a, 2 * b, 2 * c)),
               collision=Shape.superellipsoid((a, b, c), exponent))  # the inertia from the mass (closed form)
    scene.floating(PART, xyz=(0, 0, 1))
    return scene.urdf()


def random_unit_quaternion(rng):
    """(w, x, y, z) uniform on the unit sphere S^3, hence a rotation uniform on SO(3) (the Haar measure)."""
    while True:
        q = rng.normal(size=4)
        norm = np.linalg.norm(q)
        if norm > 1e-6:
            return q / norm


def support_distance(half_extents, exponent, n_B):
    """max over the superellipsoid of n_B . x (m): the dual norm, (sum |a_i n_i|^q)^(1/q) with 1/p + 1/q = 1."""
    q = exponent / (exponent - 1.0)
    return float(np.sum(np.abs(np.asarray(half_extents) * n_B) ** q) ** (1.0 / q))


def draw_drop(index, arguments):
    """The random initial condition of drop `index`: quaternion q_WB (w x y z) and angular velocity w_WB (rad/s)."""
    rng = np.random.default_rng([arguments.seed, index])
    q_WB = random_unit_quaternion(rng)
    spin_axis = random_unit_quaternion(rng)[1:]  # an isotropic direction
    spin_axis /= np.linalg.norm(spin_axis)
    w_WB = spin_axis * rng.uniform(0.0, arguments.spin_max)
    return q_WB, w_WB


def set_initial_state(model, state, slot, q_WB, w_WB, arguments):
    """Poses the part in orientation q_WB with its lowest point --height above z = 0, spinning at w_WB. Returns the
    centre's height (m)."""
    q = state.q.copy()
    q[7 * slot + 3: 7 * slot + 7] = q_WB
    state.q = q  # checked: a unit quaternion
    R_WB = state.pose(model, model.moving_bodies[slot])[1]
    down_B = R_WB.T @ np.array([0.0, 0.0, -1.0])
    centre_height = arguments.height + support_distance(arguments.half_extents, arguments.exponent, down_B)
    q[7 * slot: 7 * slot + 3] = (0.0, 0.0, centre_height)
    state.q = q
    v = np.zeros(model.nv)
    v[6 * slot + 3: 6 * slot + 6] = w_WB
    state.v = v
    return centre_height


def resting_face(R_WB):
    """(face name, tilt in degrees): the body axis that points most nearly down, and its angle from straight down."""
    down_B = R_WB.T @ np.array([0.0, 0.0, -1.0])
    axis = int(np.argmax(np.abs(down_B)))
    sign = "+" if down_B[axis] > 0 else "-"
    tilt = math.degrees(math.acos(min(1.0, abs(down_B[axis]))))
    return sign + "xyz"[axis], tilt


def mechanical_energy(model, state, part_slot, mass, g):
    """Kinetic plus gravitational energy, J (the ground is at z = 0)."""
    return implicit_sim.kinetic_energy(model, state) + mass * g * state.q[7 * part_slot + 2]


def simulate_drop(model, options, index, arguments):
    """Steps one drop until at rest, --max-time, or a step that could not advance. Returns its result row."""
    body = model.find_body(PART)
    slot = model.velocity_slot(body)
    mass, g = model.mass(body), -model.gravity[2]
    q_WB, w_WB = draw_drop(index, arguments)
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    centre_height = set_initial_state(model, state, slot, q_WB, w_WB, arguments)
    energy_start = mechanical_energy(model, state, slot, mass, g)
    largest_energy_rise = 0.0
    rest_since, steps, nonconverged, iterations, faults = None, 0, 0, 0, []
    while state.t < arguments.max_time - 1e-12:
        report = implicit_sim.step(model, options, state, data)
        steps += 1
        iterations += report.iterations
        if not report.converged:
            nonconverged += 1
            faults.append(f"t={state.t:.3f} s {report.fault} (residual {report.residual:.1e})")
        if not report.advanced:
            break  # the state is unchanged: stepping again would repeat the same failed step
        largest_energy_rise = max(largest_energy_rise, mechanical_energy(model, state, slot, mass, g) - energy_start)
        if implicit_sim.kinetic_energy(model, state) < arguments.rest_energy:
            rest_since = state.t if rest_since is None else rest_since
            if state.t - rest_since >= arguments.rest_hold - 1e-12:
                break
        else:
            rest_since = None
    at_rest = rest_since is not None and state.t - rest_since >= arguments.rest_hold - 1e-12
    p_WB, R_WB = state.pose(model, body)
    face, tilt = resting_face(R_WB)
    # Flat on a face, the centre sits at that face's half extent above the ground.
    height_error = p_WB[2] - arguments.half_extents["xyz".index(face[1])]
    if nonconverged:
        outcome = "not_converged"
    elif largest_energy_rise > arguments.energy_rise_tolerance:
        outcome = "energy_rise"
    else:
        outcome = "rest" if at_rest else "not_at_rest"
    return {"drop": index, "outcome": outcome, "face": face, "tilt_deg": tilt,
            "centre_height_error_m": height_error,
            "time_to_rest_s": rest_since if at_rest else None, "end_time_s": state.t, "steps": steps,
            "nonconverged_steps": nonconverged, "newton_iterations": iterations,
            "energy_rise_J": largest_energy_rise, "release_height_m": centre_height,
            "q_w": q_WB[0], "q_x": q_WB[1], "q_y": q_WB[2], "q_z": q_WB[3],
            "w_x": w_WB[0], "w_y": w_WB[1], "w_z": w_WB[2], "faults": "; ".join(faults)}


def summarize(rows, arguments, wall_time):
    counted = [r for r in rows if r["outcome"] == "rest"]
    times = [r["time_to_rest_s"] for r in counted]
    return {
        "samples": len(rows), "seed": arguments.seed, "half_extents_m": list(arguments.half_extents),
        "exponent": arguments.exponent, "mass_kg": arguments.mass, "mu": arguments.mu,
        "height_m": arguments.height, "spin_max_rad_s": arguments.spin_max, "h_s": arguments.h,
        "scheme": arguments.scheme, "rest_energy_J": arguments.rest_energy, "rest_hold_s": arguments.rest_hold,
        "max_time_s": arguments.max_time,
        "face_counts": {face: sum(r["face"] == face for r in counted) for face in FACES},
        "counted": len(counted),
        "not_at_rest": sum(r["outcome"] == "not_at_rest" for r in rows),
        "not_converged_drops": sum(r["outcome"] == "not_converged" for r in rows),
        "energy_rise_drops": sum(r["outcome"] == "energy_rise" for r in rows),
        "nonconverged_steps": sum(r["nonconverged_steps"] for r in rows),
        "steps": sum(r["steps"] for r in rows),
        "time_to_rest_s": {"mean": float(np.mean(times)), "max": float(np.max(times))} if times else None,
        "largest_tilt_at_rest_deg": max((r["tilt_deg"] for r in counted), default=None),
        "largest_centre_height_error_at_rest_m": max((abs(r["centre_height_error_m"]) for r in counted), default=None),
        "largest_energy_rise_J": max(r["energy_rise_J"] for r in rows),
        "wall_time_s": wall_time,
    }


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if v is None else repr(float(v)) if isinstance(v, float) else v) for k, v in row.items()})


def plot(summary, rows, path):
    figure, (faces_axis, time_axis) = plt.subplots(1, 2, figsize=(11, 4.2))
    counts = [summary["face_counts"][face] for face in FACES]
    bars = faces_axis.bar(FACES, counts, color="tab:blue")
    faces_axis.bar_label(bars)
    a, b, c = summary["half_extents_m"]
    faces_axis.set(xlabel="body axis pointing down (resting face)", ylabel="drops")
    faces_axis.set_title(f"{summary['counted']} of {summary['samples']} drops at rest ({summary['not_at_rest']} not "
                         f"at rest, {summary['not_converged_drops']} not converged, {summary['energy_rise_drops']} "
                         f"gained energy)", fontsize=9)
    faces_axis.text(0.02, 0.97, f"half extents {a:g} x {b:g} x {c:g} m", transform=faces_axis.transAxes, va="top",
                    fontsize=8)
    times = [r["time_to_rest_s"] for r in rows if r["outcome"] == "rest"]
    time_axis.hist(times, bins=30, color="tab:green")
    time_axis.set(xlabel="time to rest (s)", ylabel="drops", title="Time to rest")
    for axis in (faces_axis, time_axis):
        axis.grid(alpha=0.3, axis="y")
    figure.suptitle(f"Monte Carlo drop, seed {summary['seed']}, h = {summary['h_s']:g} s, scheme {summary['scheme']}")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def print_summary(summary):
    print(f"{'face':>5} {'drops':>6} {'share':>6}")
    for face in FACES:
        count = summary["face_counts"][face]
        print(f"{face:>5} {count:6d} {count / max(1, summary['counted']):6.1%}")
    print(f"counted (at rest, every step converged): {summary['counted']} of {summary['samples']}; "
          f"not at rest after {summary['max_time_s']:g} s: {summary['not_at_rest']}; "
          f"drops with non-converged steps: {summary['not_converged_drops']} "
          f"({summary['nonconverged_steps']} of {summary['steps']} steps); drops whose energy rose: "
          f"{summary['energy_rise_drops']}")
    if summary["time_to_rest_s"]:
        times = summary["time_to_rest_s"]
        print(f"time to rest: mean {times['mean']:.3f} s, max {times['max']:.3f} s; at rest: largest tilt "
              f"{summary['largest_tilt_at_rest_deg']:.2g} deg, largest error of the centre's height "
              f"{summary['largest_centre_height_error_at_rest_m']:.2g} m; largest rise of mechanical energy"
              f" {summary['largest_energy_rise_J']:.2g} J; wall time {summary['wall_time_s']:.1f} s")


def main(argv=None):
    arguments = parse_arguments(argv)
    out = pathlib.Path(arguments.out)
    out.mkdir(parents=True, exist_ok=True)
    scene_text = part_scene(arguments.half_extents, arguments.exponent, arguments.mass, arguments.mu, arguments.e_roll)
    (out / "part_drop.urdf").write_text(scene_text)
    model = implicit_sim.load_scene_string(scene_text, name="part_drop")
    options = implicit_sim.StepperOptions()
    options.h = arguments.h
    options.scheme = arguments.scheme
    if arguments.newton_max_iterations is not None:
        options.newton.max_iterations = arguments.newton_max_iterations
    start = time.monotonic()
    rows = []
    for index in range(arguments.samples):
        row = simulate_drop(model, options, index, arguments)
        if row["outcome"] == "not_converged":
            print(f"drop {index}: {row['nonconverged_steps']} non-converged steps, not counted: {row['faults']}")
        elif row["outcome"] == "energy_rise":
            print(f"drop {index}: its mechanical energy rose by {row['energy_rise_J']:.3g} J, not counted")
        rows.append(row)
    summary = summarize(rows, arguments, time.monotonic() - start)
    write_csv(rows, out / "drops.csv")
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    plot(summary, rows, out / "faces.png")
    print_summary(summary)
    print(f"wrote {out / 'drops.csv'}, {out / 'summary.json'}, {out / 'faces.png'}, {out / 'part_drop.urdf'}")
    return 0 if summary["counted"] > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
