#!/usr/bin/python3
"""Friction sweep over P2: the spin of a sphere on a plane decays linearly under the torsional friction moment.

What it shows: editing a scene's text with xml.etree (the `mu` attribute of the default <friction> element of
scenes/p2_sphere_spinning.urdf), loading it with implicit_sim.load_scene_string, stepping it from Python, reading the
state (w_z) and the contacts (the torsional moment), and checking the simulation against the closed form.

The physics (doc/scenes.md; the scene's comment): a sphere of mass m and inertia I about its centre spins at w0 about
the vertical on the plane z = 0. Its contact point does not slide (v_t = 0), so only the torsional friction acts: while
it spins, its moment is the largest allowed, e_r mu N with N = m g, and

    dw_z/dt = -e_r mu m g / I          (rad/s^2)
    t_stop  = w0 I / (e_r mu m g)      (s)

The scene's own values (mu = 0.2, e_r = 0.4 m, m = 1 kg, I = 0.4 kg m^2, w0 = 1.962 rad/s) give a slope of -1.962
rad/s^2 and t_stop = 1 s.

What is measured, per mu: the slope of w_z (least squares over the step ends while it still spins), the stop time (the
first step end with w_z = 0 to round-off) and the largest deviation of the contact's torsional moment from e_r mu N
while it spins. Exit status 1 when a slope differs from the closed form by more than --slope-tolerance (relative), or
a stop time by more than one step h: see check_row for why these bounds.

Run (after `source /tmp/implicit_sim_ws/devel/setup.bash`, from the repository root):
    /usr/bin/python3 examples/friction_sweep.py                    # 20 values of mu in [0.05, 1], h = 1 ms
    /usr/bin/python3 examples/friction_sweep.py --quick            # 4 values, for tests
    /usr/bin/python3 examples/friction_sweep.py --mu-min 0.1 --mu-max 2 --count 12 --h 0.0005 --out /tmp/sweep

Writes into --out (default examples_output/friction_sweep/):
    friction_sweep.csv   one row per mu: measured and closed-form slope and stop time, their errors
    friction_sweep.png   slope and stop time against mu (closed form as lines), and w_z(t) for a few mu
and prints the same table.
"""
import argparse
import csv
import math
import pathlib
import sys
import xml.etree.ElementTree as ET

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import implicit_sim  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]
SCENE = REPO / "scenes" / "p2_sphere_spinning.urdf"
SPIN_AXIS = 5  # index of w_z in v = (v_WB, w_WB) of the one moving body


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mu-min", type=float, default=0.05, help="smallest friction coefficient (default 0.05)")
    parser.add_argument("--mu-max", type=float, default=1.0, help="largest friction coefficient (default 1)")
    parser.add_argument("--count", type=int, default=20, help="number of values of mu, evenly spaced (default 20)")
    parser.add_argument("--h", type=float, default=0.001, help="time step, s (default 0.001)")
    parser.add_argument("--scheme", choices=("rattle", "paper"), default="rattle",
                        help="time-stepping scheme (default rattle, the simulator's default)")
    parser.add_argument("--max-time", type=float, default=30.0, help="longest simulated time per mu, s (default 30)")
    parser.add_argument("--slope-tolerance", type=float, default=1e-6,
                        help="largest relative slope error accepted (default 1e-6; see check_row)")
    parser.add_argument("--quick", action="store_true", help="4 values of mu in [0.2, 1] (for tests)")
    parser.add_argument("--out", default="examples_output/friction_sweep", help="output directory")
    arguments = parser.parse_args(argv)
    if arguments.quick:
        arguments.mu_min, arguments.mu_max, arguments.count = 0.2, 1.0, 4
    if not 0 < arguments.mu_min <= arguments.mu_max or arguments.count < 1:
        parser.error("need 0 < --mu-min <= --mu-max and --count >= 1")
    return arguments


def scene_with_friction(mu):
    """The P2 scene's URDF text with the default friction coefficient set to mu."""
    tree = ET.parse(SCENE)
    (friction,) = [f for f in tree.getroot().iter("friction") if "link1" not in f.attrib]  # the default for every pair
    friction.set("mu", repr(mu))
    return ET.tostring(tree.getroot(), encoding="unicode")


def closed_form(model, ball, w0):
    """(slope of w_z in rad/s^2, stop time in s) of the sphere's spin."""
    friction = model.pair_friction(0)
    mass = model.mass(ball)  # kg
    inertia_zz = model.inertia(ball)[2, 2]  # kg m^2
    g = -model.gravity[2]  # m/s^2
    moment = friction["e_r"] * friction["mu"] * mass * g  # N m, the largest torsional moment
    return -moment / inertia_zz, w0 * inertia_zz / moment


def simulate_spin_down(mu, h, scheme, max_time):
    """Steps P2 with friction mu until the spin has stopped for 10 steps (or max_time). Returns a dict of the
    trajectory t, w_z, the torsional moment per step, the closed form and the step counts."""
    model = implicit_sim.load_scene_string(scene_with_friction(mu), name=f"p2_mu_{mu:g}")
    ball = model.find_body("ball")
    assert model.pair_friction(0)["mu"] == mu, "the edited scene did not load with the new mu"
    options = implicit_sim.StepperOptions()
    options.h = h
    options.scheme = scheme
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    w0 = float(state.v[SPIN_AXIS])
    slope, t_stop = closed_form(model, ball, w0)
    times, spins, moments, normal_forces = [state.t], [w0], [math.nan], [math.nan]
    stopped_steps, nonconverged = 0, 0
    while state.t < max_time and stopped_steps < 10:
        report = implicit_sim.step(model, options, state, data)
        nonconverged += not report.converged
        contacts = data.contacts
        times.append(state.t)
        spins.append(float(state.v[SPIN_AXIS]))
        moments.append(float(np.sum(contacts["torsional_moment"])))  # N m, on the ball about the normal
        normal_forces.append(float(np.sum(contacts["normal_force"])))
        stopped_steps = stopped_steps + 1 if abs(spins[-1]) <= 1e-9 * abs(w0) else 0
    friction = model.pair_friction(0)
    return {"mu": mu, "w0": w0, "t": np.array(times), "w_z": np.array(spins), "moment": np.array(moments),
            "normal_force": np.array(normal_forces), "e_r": friction["e_r"], "slope_closed": slope,
            "t_stop_closed": t_stop, "nonconverged": nonconverged, "steps": len(times) - 1}


def measure(run, h):
    """The measured slope (least squares over the step ends while it spins), stop time and torsional moment error."""
    spinning = np.abs(run["w_z"]) > 1e-9 * abs(run["w0"])
    slope_measured = float(np.polyfit(run["t"][spinning], run["w_z"][spinning], 1)[0])
    stopped = np.flatnonzero(~spinning)
    t_stop_measured = float(run["t"][stopped[0]]) if stopped.size else math.nan
    # While it spins through a whole step, the moment is the largest allowed: e_r mu N (the index 0 row is t = 0).
    sliding_steps = np.flatnonzero(spinning)[1:]
    largest_moment = run["e_r"] * run["mu"] * run["normal_force"][sliding_steps]
    moment_error = float(np.max(np.abs(np.abs(run["moment"][sliding_steps]) - largest_moment) / largest_moment))
    return {"mu": run["mu"], "slope_measured": slope_measured, "slope_closed": run["slope_closed"],
            "slope_rel_error": abs(slope_measured / run["slope_closed"] - 1.0),
            "t_stop_measured": t_stop_measured, "t_stop_closed": run["t_stop_closed"],
            "t_stop_error": t_stop_measured - run["t_stop_closed"], "moment_rel_error": moment_error,
            "steps": run["steps"], "nonconverged_steps": run["nonconverged"], "h": h}


def check_row(row, slope_tolerance):
    """The reasons a row fails, empty when it passes.

    Slope: while the sphere spins, the torsional moment is constant (e_r mu m g) and the step integrates the angular
    velocity implicitly with that end-of-step moment, so w_z falls by exactly h e_r mu m g / I per step: the discrete
    slope equals the closed form up to the Newton tolerance (1e-12 on the residual) and round-off, about 1e-12
    relative. The default bar of 1e-6 leaves six orders of margin for round-off over thousands of steps and for other
    solver options, and still catches any modelling error (a wrong e_r, mu, N or I shows at the percent level).
    Stop time: the spin stops inside the step that contains t_stop, and the step reports w_z = 0 at its end, so the
    measured stop lies in [t_stop, t_stop + h] (h plus round-off)."""
    problems = []
    if row["nonconverged_steps"]:
        problems.append(f"{row['nonconverged_steps']} non-converged steps")
    if not row["slope_rel_error"] <= slope_tolerance:
        problems.append(f"slope error {row['slope_rel_error']:.2e} > {slope_tolerance:g}")
    if not -1e-9 <= row["t_stop_error"] <= row["h"] + 1e-9:
        problems.append(f"stop time off by {row['t_stop_error']:+.2e} s, outside [0, h]")
    return problems


def print_table(rows):
    header = (f"{'mu':>6} {'slope (rad/s^2)':>16} {'closed form':>12} {'rel. error':>10} {'t_stop (s)':>10} "
              f"{'closed form':>12} {'diff (s)':>9} {'moment err':>10} {'steps':>6}")
    print(header)
    print("-" * len(header))
    for r in rows:
        print(f"{r['mu']:6.3f} {r['slope_measured']:16.9f} {r['slope_closed']:12.6f} {r['slope_rel_error']:10.1e} "
              f"{r['t_stop_measured']:10.4f} {r['t_stop_closed']:12.6f} {r['t_stop_error']:+9.1e} "
              f"{r['moment_rel_error']:10.1e} {r['steps']:6d}")


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: repr(float(v)) if isinstance(v, float) else v for k, v in row.items()})


def plot(rows, runs, slope_tolerance, path):
    mu = np.array([r["mu"] for r in rows])
    mu_fine = np.linspace(mu.min(), mu.max(), 200)
    # Both closed forms are linear in mu (slope) and in 1/mu (stop time): scale the first row's.
    slope_per_mu = rows[0]["slope_closed"] / rows[0]["mu"]
    stop_times_mu = rows[0]["t_stop_closed"] * rows[0]["mu"]
    figure, axes = plt.subplots(2, 2, figsize=(11, 8))
    axes = axes.ravel()
    axes[0].plot(mu_fine, slope_per_mu * mu_fine, "k-", label="closed form $-e_r \\mu m g / I$")
    axes[0].plot(mu, [r["slope_measured"] for r in rows], "o", color="tab:red", label="simulated")
    axes[0].set(xlabel="friction coefficient $\\mu$", ylabel="$dw_z/dt$ (rad/s$^2$)", title="Spin decay rate")
    axes[1].plot(mu_fine, stop_times_mu / mu_fine, "k-", label="closed form $w_0 I / (e_r \\mu m g)$")
    axes[1].plot(mu, [r["t_stop_measured"] for r in rows], "o", color="tab:red", label="simulated")
    axes[1].set(xlabel="friction coefficient $\\mu$", ylabel="stop time (s)", title="Time to stop")
    shown = runs[:: max(1, len(runs) // 5)]
    for run in shown:
        axes[2].plot(run["t"], run["w_z"], label=f"$\\mu$ = {run['mu']:.3g}")
    axes[2].set(xlabel="t (s)", ylabel="$w_z$ (rad/s)", title="Spin against time",
                xlim=(0, 1.2 * max(r["t_stop_closed"] for r in shown)))
    tiny = 1e-17  # floor for exact zeros on the log scale
    axes[3].semilogy(mu, [max(r["slope_rel_error"], tiny) for r in rows], "o", color="tab:red",
                     label="simulated slope")
    axes[3].axhline(slope_tolerance, color="k", ls="--", label=f"tolerance {slope_tolerance:g}")
    axes[3].set(xlabel="friction coefficient $\\mu$", ylabel="|measured / closed form - 1|",
                title="Relative slope error", ylim=(tiny, 1.0))
    for axis in axes:
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    figure.suptitle(f"P2: sphere spinning on a plane, h = {rows[0]['h']:g} s")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main(argv=None):
    arguments = parse_arguments(argv)
    out = pathlib.Path(arguments.out)
    out.mkdir(parents=True, exist_ok=True)
    runs, rows = [], []
    for mu in np.linspace(arguments.mu_min, arguments.mu_max, arguments.count):
        run = simulate_spin_down(float(mu), arguments.h, arguments.scheme, arguments.max_time)
        runs.append(run)
        rows.append(measure(run, arguments.h))
    print(f"P2 friction sweep: {SCENE.name}, w0 = {runs[0]['w0']:g} rad/s, e_r = {runs[0]['e_r']:g} m, "
          f"h = {arguments.h:g} s, scheme {arguments.scheme}")
    print_table(rows)
    write_csv(rows, out / "friction_sweep.csv")
    plot(rows, runs, arguments.slope_tolerance, out / "friction_sweep.png")
    print(f"wrote {out / 'friction_sweep.csv'} and {out / 'friction_sweep.png'}")
    failures = [(row["mu"], problem) for row in rows for problem in check_row(row, arguments.slope_tolerance)]
    for mu, problem in failures:
        print(f"FAIL mu = {mu:g}: {problem}", file=sys.stderr)
    if failures:
        return 1
    worst = max(rows, key=lambda r: r["slope_rel_error"])
    print(f"OK: every slope within {arguments.slope_tolerance:g} of the closed form "
          f"(worst {worst['slope_rel_error']:.1e}"
          f" at mu = {worst['mu']:g}), every stop time within one step after the closed form")
    return 0


if __name__ == "__main__":
    sys.exit(main())
