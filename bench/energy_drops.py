#!/usr/bin/python3
"""Energy and cost of the time-stepping schemes on random drops and piles, side by side in one run (JSONL).

A passive part dropped on a plane, or a pile settling, can only lose mechanical energy (kinetic plus gravitational):
contact, friction and impacts do no positive work. This benchmark counts, per scheme and time step, the steps that
raise it, the drops that end above their start energy, the steps that did not converge, the energy-guard fallbacks
(StepReport.energy_fallbacks) and the wall time.

Drops: drop i is shape kind i % 5 (box, superellipsoid, cylinder, ellipsoid, prism), friction mu = (0.2, 0.5, 1.0)
[(i // 5) % 3] (and rolling resistance --e-roll), drawn from its own generator seeded with (--seed, i): an orientation uniform on SO(3), a spin of
uniform direction and magnitude in [0, 8] rad/s, the part's centre 0.1-0.3 m above the plane. Every drop runs
--duration seconds. Piles: the given scene files, --pile-duration seconds.

Run (after `source /tmp/implicit_sim_ws/devel/setup.bash`, from the repository root):
    /usr/bin/python3 bench/energy_drops.py                       # 100 drops x h 0.01, 0.005 x both schemes, 30-part pile
    /usr/bin/python3 bench/energy_drops.py --drops 30 --piles    # drops only
    /usr/bin/python3 bench/energy_drops.py --piles --dump-dir DIR # and step cases of steps the guard rejected

One JSON line per (case, scheme, h): case ("drops" or the pile's file name), scheme, h_s, runs, steps, wall_time_s,
rising_steps (steps whose energy rose by more than --rise-tolerance J), rising_steps_1pct (rose by more than 1 % of
the run's start energy), guard_violations (rose by more than the energy guard's allowance, computed here), largest_step_rise_J, runs_above_start (end energy above start + --rise-tolerance),
nonconverged_steps, energy_fallbacks, paper_fallbacks, damping_steps, newton_iterations, at_rest (runs whose kinetic energy is below 1e-4 J at the
end). Then, with both schemes measured, one line per (case, h) with the wall-time ratio rattle / paper.
"""
import argparse
import json
import math
import pathlib
import sys
import time

import numpy as np

import implicit_sim
from implicit_sim.scene import Scene, Shape

KINDS = ("box", "superellipsoid", "cylinder", "ellipsoid", "prism")
MUS = (0.2, 0.5, 1.0)
REST_KINETIC_ENERGY = 1e-4  # J


def part_shape(kind):
    """The part of each kind, about 10 cm across (m)."""
    if kind == "box":
        return Shape.box((0.1, 0.07, 0.05))
    if kind == "superellipsoid":
        return Shape.superellipsoid((0.05, 0.04, 0.02), 8)
    if kind == "cylinder":
        return Shape.cylinder(0.04, 0.03)
    if kind == "ellipsoid":
        return Shape.ellipsoid((0.06, 0.04, 0.03))
    return Shape.prism(6, 0.04, 0.05)


def drop_scene_urdf(kind, mu, e_roll=0.0):
    scene = Scene(f"drop_{kind}", comment=f"a {kind} dropped on a plane, mu {mu}")
    scene.friction(mu=mu, e_t=1, e_o=1, e_r=0.01, **({"e_roll": e_roll} if e_roll > 0 else {}))
    scene.halfspace("ground")
    scene.link("part", mass=0.3, collision=part_shape(kind))
    scene.floating("part", xyz=(0, 0, 0.5))
    return scene.urdf()


def drop_scene(kind, mu, e_roll=0.0):
    return implicit_sim.load_scene_string(drop_scene_urdf(kind, mu, e_roll), name=f"drop_{kind}")


def random_rotation_quaternion(rng):
    """Uniform on SO(3) (w, x, y, z)."""
    u1, u2, u3 = rng.random(3)
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    return np.array([a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2), b * math.sin(2 * math.pi * u3),
                     b * math.cos(2 * math.pi * u3)])


def drop_start(model, index, seed):
    rng = np.random.default_rng([seed, index])
    state = implicit_sim.State.initial(model)
    q, v = state.q.copy(), state.v.copy()
    q[2] = 0.1 + 0.2 * rng.random()
    q[3:7] = random_rotation_quaternion(rng)
    direction = rng.normal(size=3)
    v[3:6] = direction / np.linalg.norm(direction) * 8.0 * rng.random()
    state.q, state.v = q, v
    return state


def energies(model, state):
    """(kinetic, gravitational) energy, J."""
    g = model.gravity
    potential = 0.0
    for slot, body in enumerate(model.moving_bodies):
        potential -= model.mass(body) * float(np.dot(g, state.q[7 * slot:7 * slot + 3]))
    return implicit_sim.kinetic_energy(model, state), potential


def mechanical_energy(model, state):
    """Kinetic plus gravitational energy, J."""
    return sum(energies(model, state))


def guard_allowance(model, kinetic_start, kinetic_end, gravity_work, first_order_share=0.0):
    """The energy guard's allowance for a step of a scene whose only external force is gravity (doc/method.md, "The
    energy guard"), computed here independently of the simulator (J): a share of the energy in motion, 1 % for the
    RATTLE step and 1 % + first_order_share for the paper's first-order step (h times the largest angular speed: its
    rotation takes the inertia at one end of the step), and the work of the weights over 1e-8 m."""
    weight = sum(model.mass(b) for b in model.moving_bodies) * float(np.linalg.norm(model.gravity))
    share = 0.01 + first_order_share
    return share * (max(kinetic_start, kinetic_end) + abs(gravity_work)) + 1e-8 * weight


def largest_angular_speed(model, *states):
    """rad/s, over the moving bodies of the given states."""
    return max(float(np.linalg.norm(s.v[6 * k + 3:6 * k + 6])) for s in states for k in range(model.num_moving))


class Tally:
    def __init__(self, case, scheme, h):
        self.row = {"case": case, "scheme": scheme, "h_s": h, "runs": 0, "steps": 0, "wall_time_s": 0.0,
                    "rising_steps": 0, "rising_steps_1pct": 0, "largest_step_rise_J": 0.0, "runs_above_start": 0,
                    "guard_violations": 0, "nonconverged_steps": 0, "energy_fallbacks": 0, "paper_fallbacks": 0, "damping_steps": 0, "newton_iterations": 0,
                    "at_rest": 0}

    def run(self, model, options, state, duration, tolerance, dump=None):
        """dump: None, or a Dump that writes a step case of each step whose energy guard fired."""
        row = self.row
        data = implicit_sim.Data(model)
        kinetic, potential = energies(model, state)
        energy_start = energy = kinetic + potential
        started = time.perf_counter()
        steps = int(round(duration / options.h))
        for step in range(steps):
            omega_start = largest_angular_speed(model, state)
            before = (state.copy(), implicit_sim.save_warm_start(data)) if dump else None
            report = implicit_sim.step(model, options, state, data)
            if dump and report.energy_fallbacks:
                dump.write(options, before, data, report, step)
            row["steps"] += 1
            row["newton_iterations"] += report.iterations
            row["energy_fallbacks"] += report.energy_fallbacks
            row["paper_fallbacks"] += report.paper_fallbacks
            row["damping_steps"] += report.damping_steps
            if not report.converged:
                row["nonconverged_steps"] += 1
            if not report.advanced:
                break
            kinetic_next, potential_next = energies(model, state)
            energy_next = kinetic_next + potential_next
            rise = energy_next - energy
            first_order = options.h * max(omega_start, largest_angular_speed(model, state)) \
                if options.scheme == "paper" or report.paper_fallbacks or report.damping_steps else 0.0  # the paper's step
            row["guard_violations"] += rise > guard_allowance(model, kinetic, kinetic_next, potential - potential_next,
                                                              first_order)
            kinetic, potential = kinetic_next, potential_next
            row["rising_steps"] += rise > tolerance
            row["rising_steps_1pct"] += rise > 0.01 * abs(energy_start)
            row["largest_step_rise_J"] = max(row["largest_step_rise_J"], rise)
            energy = energy_next
        row["wall_time_s"] += time.perf_counter() - started
        row["runs"] += 1
        row["runs_above_start"] += energy > energy_start + tolerance
        row["at_rest"] += implicit_sim.kinetic_energy(model, state) < REST_KINETIC_ENERGY


class Dump:
    """Writes step cases (implicit_sim_replay) of the steps whose energy guard fired, the first of each run (scene and
    h), up to `limit`, into `directory`."""

    def __init__(self, directory, limit):
        self.directory, self.limit, self.written = pathlib.Path(directory), limit, 0
        self.urdf = self.scene_name = self.label = None
        self.runs_dumped = set()

    def scene(self, urdf, scene_name, label):
        self.urdf, self.scene_name, self.label = urdf, scene_name, label

    def write(self, options, before, data, report, step):
        if self.written >= self.limit or (self.label, options.h) in self.runs_dumped:
            return
        self.runs_dumped.add((self.label, options.h))
        self.directory.mkdir(parents=True, exist_ok=True)
        name = f"{self.label}_h{options.h:g}_step{step:04d}".replace(".", "p")
        origin = (f"bench/energy_drops.py --dump-dir: {self.label}, {options.scheme} h = {options.h:g}, step {step}, "
                  f"energy guard fired")
        implicit_sim.write_step_case(str(self.directory / f"{name}.case"), name, origin, self.urdf, self.scene_name,
                                     options, before[0], before[1], data, report)
        self.written += 1


def make_options(scheme, h):
    options = implicit_sim.StepperOptions()
    options.scheme = scheme
    options.h = h
    return options


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--drops", type=int, default=100, help="number of drops (default 100)")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--duration", type=float, default=2.0, help="s of each drop (default 2)")
    parser.add_argument("--h", type=float, nargs="+", default=(0.01, 0.005), help="time steps, s")
    parser.add_argument("--schemes", nargs="+", default=("paper", "rattle"))
    parser.add_argument("--piles", nargs="*", default=("scenes/pile_drop.urdf",), help="pile scene files")
    parser.add_argument("--pile-duration", type=float, default=2.0)
    parser.add_argument("--e-roll", type=float, default=0.0, help="rolling resistance of the drops, m (default 0)")
    parser.add_argument("--rise-tolerance", type=float, default=1e-6, help="J (default 1e-6)")
    parser.add_argument("--dump-dir", help="write a step case of the first step of each run whose energy guard fired")
    parser.add_argument("--dump-max", type=int, default=50, help="at most this many cases (default 50)")
    arguments = parser.parse_args(argv)
    dump = Dump(arguments.dump_dir, arguments.dump_max) if arguments.dump_dir else None
    models = {(kind, mu): drop_scene(kind, mu, arguments.e_roll) for kind in KINDS for mu in MUS}
    rows = []
    for h in arguments.h:
        for scheme in arguments.schemes:
            tally = Tally("drops", scheme, h)
            tally.row["e_roll_m"] = arguments.e_roll
            for i in range(arguments.drops):
                kind, mu = KINDS[i % 5], MUS[(i // 5) % 3]
                model = models[(kind, mu)]
                if dump:
                    dump.scene(drop_scene_urdf(kind, mu, arguments.e_roll), f"drop_{kind}", f"drop{i:03d}_{kind}")
                tally.run(model, make_options(scheme, h), drop_start(model, i, arguments.seed), arguments.duration,
                          arguments.rise_tolerance, dump)
            rows.append(tally.row)
            print(json.dumps(tally.row), flush=True)
        for pile in arguments.piles:
            model = implicit_sim.load_scene(pile)
            if dump:
                dump.scene(pathlib.Path(pile).read_text(), model.name, pathlib.Path(pile).stem)
            for scheme in arguments.schemes:
                tally = Tally(pathlib.Path(pile).name, scheme, h)
                tally.run(model, make_options(scheme, h), implicit_sim.State.initial(model), arguments.pile_duration,
                          arguments.rise_tolerance, dump)
                rows.append(tally.row)
                print(json.dumps(tally.row), flush=True)
    if {"paper", "rattle"} <= set(arguments.schemes):
        for case in dict.fromkeys(r["case"] for r in rows):
            for h in arguments.h:
                time_of = {r["scheme"]: r["wall_time_s"] for r in rows if r["case"] == case and r["h_s"] == h}
                print(json.dumps({"case": case, "h_s": h, "wall_time_ratio_rattle_paper":
                                  time_of["rattle"] / time_of["paper"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
