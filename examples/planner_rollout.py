#!/usr/bin/python3
"""A planner's rollouts: push a box across a table to a target by trying each push in the simulator first.

What it shows: the simulator as a planner's model. At each decision the planner saves the state and the solver's warm
start (`state.copy()`, `implicit_sim.save_warm_start`), rolls out every candidate push for a short horizon, reads the
contacts of each rollout step (`data.contacts`: normal forces, gaps, contact points, slip speeds) to reject and score
the candidates, restores the saved state and warm start (`state.assign`, `implicit_sim.restore_warm_start`), and then
applies the best push for real. Because the restore is exact, the real step reproduces the chosen rollout bit for bit;
the script checks this at every decision.

The scene: a box (0.2 x 0.2 x 0.3 m, 1 kg) standing on a table (the plane z = 0), mu = 0.3. A candidate push is a
force applied for one decision period (0.1 s) at a point of the box's side facing away from the push, at a low or a
high point, in a direction near the direction to the target, turned into a wrench with `implicit_sim.wrench_at_point`
every step (the point moves with the box). Each rollout is the push followed by a coast (no force) to the end of the
horizon, and is judged from the contacts:
  - contact lost (rejected): the box-table pair has no normal force, or a positive gap: the push lifts the box off;
  - tipping (rejected): the contact point, which the step places at the centre of pressure of the flat contact, comes
    within --stability-margin of the edge of the box's base: the push (or the friction moment while sliding) is about
    to tip the box over. A high push of 7 N tips it; a low one slides it;
  - otherwise the score is the distance from the box's centre to the target at the end of the horizon plus
    --slip-weight times the slip speed there (a box still sliding has not arrived yet).
The decision log prints, per decision, the best and rejected candidates; the run ends when the box is within
--tolerance of the target and at rest (exit status 0), or after --max-decisions (exit status 1).

Run (after `source /tmp/implicit_sim_ws/devel/setup.bash`, from the repository root):
    /usr/bin/python3 examples/planner_rollout.py                      # target (1, 0.5) m, 33 candidates
    /usr/bin/python3 examples/planner_rollout.py --quick              # a nearer target, 15 candidates (for tests)
    /usr/bin/python3 examples/planner_rollout.py --target 0.3 -0.4 --tolerance 0.01 --out /tmp/push

Writes into --out (default examples_output/planner_rollout/):
    decisions.csv      one row per decision: time, box pose, chosen push, its predicted score, the candidates rejected
                       for lost contact and for tipping, whether the real step matched the rollout bit for bit
    summary.json       the parameters and the outcome (reached, final distance, decisions, rejections, wall time)
    path.png           the box's path on the table (top view) and its distance to the target against time
    box_push.urdf      the scene that was simulated
"""
import argparse
import csv
import dataclasses
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

BOX = "box"
TABLE = "table"
HALF_EXTENTS = np.array([0.1, 0.1, 0.15])  # m, the box's half size along its x, y, z
MASS = 1.0  # kg
MU = 0.3


@dataclasses.dataclass(frozen=True)
class Push:
    """A candidate: a force of `force` N for one decision period, `heading` degrees from the direction to the target
    (counterclockwise seen from above), horizontal at `height` m above the box's base, or, with an `elevation` (degrees
    up from horizontal), on a line through the centre of mass (a scooping push: no moment about the centre)."""
    force: float
    heading: float
    height: float = 0.0
    elevation: float = 0.0

    def label(self):
        if self.force == 0.0:
            return "coast"
        if self.elevation:
            return f"{self.force:g} N up {self.elevation:g} deg {self.heading:+g} deg"
        where = "high" if self.height > HALF_EXTENTS[2] else "low"
        return f"{self.force:g} N {where} {self.heading:+g} deg"


@dataclasses.dataclass
class Rollout:
    push: Push
    rejected: str = ""  # the reason, empty when accepted
    detail: str = ""
    score: float = math.inf  # m
    end_distance: float = math.inf  # m
    end_slip: float = 0.0  # m/s
    state_after_push: object = None  # the State at the end of the push, to compare with the real step


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--target", type=float, nargs=2, default=(1.0, 0.5), metavar=("X", "Y"),
                        help="target of the box's centre on the table, m (default 1 0.5; the box starts at 0 0)")
    parser.add_argument("--tolerance", type=float, default=0.01,
                        help="reached: the box's centre within this distance of the target, m (default 0.01) ...")
    parser.add_argument("--rest-speed", type=float, default=1e-3,
                        help="... and its speed below this, m/s (default 1e-3)")
    parser.add_argument("--decision-period", type=float, default=0.1, help="s between decisions (default 0.1)")
    parser.add_argument("--coast", type=float, default=0.6,
                        help="longest coast after the push in each rollout, s (default 0.6; it ends at rest)")
    parser.add_argument("--stability-margin", type=float, default=0.01,
                        help="reject pushes whose contact point comes within this of the base's edge, m (default 0.01)")
    parser.add_argument("--slip-weight", type=float, default=0.2,
                        help="s: the score's weight of the slip speed at the end of the horizon (default 0.2)")
    parser.add_argument("--max-decisions", type=int, default=60, help="give up after this many (default 60)")
    parser.add_argument("--h", type=float, default=0.005, help="time step, s (default 0.005)")
    parser.add_argument("--scheme", choices=("rattle", "paper"), default="rattle",
                        help="time-stepping scheme (default rattle, the simulator's default)")
    parser.add_argument("--quick", action="store_true",
                        help="target (0.25, 0.1) m and 15 candidates (for tests)")
    parser.add_argument("--out", default="examples_output/planner_rollout", help="output directory")
    arguments = parser.parse_args(argv)
    if arguments.quick:
        arguments.target = (0.25, 0.1)
    return arguments


def candidate_pushes(quick):
    """Low and high pushes at a few headings and forces, two scooping pushes, and coasting."""
    headings = (-30.0, 0.0, 30.0) if quick else (-45.0, -22.5, 0.0, 22.5, 45.0)
    forces = (4.0, 10.0) if quick else (4.0, 7.0, 10.0)  # N; sliding needs more than mu m g = 2.94 N
    low, high = 0.06, 0.26  # m above the base; the centre of mass is at 0.15 m
    pushes = [Push(force, heading, height) for height in (low, high) for force in forces for heading in headings]
    # Scooping: 20 N at 30 deg lifts 10 N > m g = 9.81 N (the box takes off); 14 N at 20 deg lifts 4.8 N, which halves
    # the friction while it pushes 13 N forward.
    pushes += [Push(20.0, 0.0, elevation=30.0), Push(14.0, 0.0, elevation=20.0)]
    return pushes + [Push(0.0, 0.0)]


def box_scene():
    a, b, c = HALF_EXTENTS
    inertia = MASS / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])  # kg m^2, the uniform solid
    scene = Scene("box_push", comment=f"examples/planner_rollout.py: a box ({2 * a} x {2 * b} x {2 * c} m, {MASS} kg) "
                  f"standing on a table, the plane z = 0;\n     mu = {MU}, e_t = e_o = 1, e_r = 0.05 m. The script "
                  "pushes it with wrenches given per step.")
    scene.friction(mu=MU, e_t=1, e_o=1, e_r=0.05)
    scene.halfspace(TABLE)
    scene.link(BOX, MASS, inertia, visual=Shape.box((2 * a, 2 * b, 2 * c)), collision=Shape.box((2 * a, 2 * b, 2 * c)))
    scene.floating(BOX, xyz=(0, 0, c))
    return scene.urdf()


class World:
    """The model, options, the live state and the solver workspace, with the box's indices."""

    def __init__(self, arguments):
        self.scene_text = box_scene()
        self.model = implicit_sim.load_scene_string(self.scene_text, name="box_push")
        self.options = implicit_sim.StepperOptions()
        self.options.h = arguments.h
        self.options.scheme = arguments.scheme
        self.state = implicit_sim.State.initial(self.model)
        self.data = implicit_sim.Data(self.model)
        self.box = self.model.find_body(BOX)
        self.slot = self.model.velocity_slot(self.box)
        self.pair = self.model.pair_index(self.box, self.model.find_body(TABLE))

    def position(self):
        """The box's centre on the table (x, y), m."""
        return self.state.q[7 * self.slot: 7 * self.slot + 2].copy()

    def yaw(self):
        """rad, the box's heading about the vertical."""
        R_WB = self.state.pose(self.model, self.box)[1]
        return math.atan2(R_WB[1, 0], R_WB[0, 0])

    def sample(self):
        """(t in s, x in m, y in m, yaw in rad) for the trajectory."""
        return (self.state.t, *self.position(), self.yaw())

    def speed(self):
        """m/s of the box's centre."""
        return float(np.linalg.norm(self.state.v[6 * self.slot: 6 * self.slot + 3]))


def push_wrench(world, push, direction_W):
    """The wrench (nv,) of `push` at this step's pose; direction_W is the horizontal unit direction to the target."""
    if push.force == 0.0:
        return None
    heading = math.radians(push.heading)
    c, s = math.cos(heading), math.sin(heading)
    u_W = np.array([c * direction_W[0] - s * direction_W[1], s * direction_W[0] + c * direction_W[1], 0.0])
    p_WB, R_WB = world.state.pose(world.model, world.box)
    u_B = R_WB.T @ u_W
    # The point of the side facing away from the push, on the line through the centre along -u_B.
    reach = min(HALF_EXTENTS[0] / max(abs(u_B[0]), 1e-12), HALF_EXTENTS[1] / max(abs(u_B[1]), 1e-12))
    elevation = math.radians(push.elevation)
    height_above_centre = -reach * math.tan(elevation) if push.elevation else push.height - HALF_EXTENTS[2]
    p_BP = np.array([-reach * u_B[0], -reach * u_B[1], height_above_centre])
    f_W = push.force * (math.cos(elevation) * u_W + np.array([0.0, 0.0, math.sin(elevation)]))
    return implicit_sim.wrench_at_point(world.model, world.state, world.box, p_WB + R_WB @ p_BP, f_W)


def contact_verdict(world, margin):
    """Why the box's contact with the table after the last step is unacceptable ('' if it is fine), with the numbers:
    read from data.contacts (normal force, gap, contact point on the box)."""
    contacts = world.data.contacts
    rows = np.flatnonzero(contacts["pair"] == world.pair)
    if rows.size == 0:
        return "contact lost", "the pair left the NCP"
    row = rows[0]
    normal_force, gap = contacts["normal_force"][row], contacts["gap"][row]
    if normal_force <= 1e-9 or gap > 1e-6:
        return "contact lost", f"normal force {normal_force:.3g} N, gap {gap:.3g} m"
    p_WB, R_WB = world.state.pose(world.model, world.box)
    p_BA = R_WB.T @ (contacts["p_WA1"][row] - p_WB)  # the contact point on the box, box frame
    edge_distance = min(HALF_EXTENTS[0] - abs(p_BA[0]), HALF_EXTENTS[1] - abs(p_BA[1]))
    if edge_distance < margin:
        where = "on" if edge_distance < 1e-5 else f"{edge_distance * 1e3:.1f} mm from"
        return "tipping", f"contact point {where} the base's edge"
    return "", ""


def slip_speed(world):
    contacts = world.data.contacts
    rows = np.flatnonzero(contacts["pair"] == world.pair)
    return float(contacts["slip_speed"][rows[0]]) if rows.size else 0.0


def roll_out(world, push, direction_W, push_steps, coast_steps, target, arguments):
    """Steps the world through the push and the coast, judging every step's contacts; stops at the first rejection."""
    result = Rollout(push)
    for k in range(push_steps + coast_steps):
        wrench = push_wrench(world, push, direction_W) if k < push_steps else None
        report = implicit_sim.step(world.model, world.options, world.state, world.data, wrench=wrench)
        if not report.converged:
            result.rejected, result.detail = "not converged", f"step {k}: {report.fault}"
            return result
        result.rejected, result.detail = contact_verdict(world, arguments.stability_margin)
        if result.rejected:
            result.detail = f"at {(k + 1) * world.options.h:.3f} s: {result.detail}"
            return result
        if k == push_steps - 1:
            result.state_after_push = world.state.copy()
        if k >= push_steps and world.speed() <= arguments.rest_speed:
            break  # at rest before the end of the horizon
    result.end_distance = float(np.linalg.norm(world.position() - target))
    result.end_slip = slip_speed(world)
    result.score = result.end_distance + arguments.slip_weight * result.end_slip
    return result


def decide(world, pushes, push_steps, coast_steps, target, arguments):
    """Rolls out every push from the same saved state and warm start; returns the rollouts, best first."""
    saved_state, saved_warm = world.state.copy(), implicit_sim.save_warm_start(world.data)
    to_target = target - world.position()
    direction_W = to_target / max(np.linalg.norm(to_target), 1e-12)
    rollouts = []
    for push in pushes:
        world.state.assign(saved_state)
        implicit_sim.restore_warm_start(world.model, saved_warm, world.data)
        rollouts.append(roll_out(world, push, direction_W, push_steps, coast_steps, target, arguments))
    world.state.assign(saved_state)  # back to where the decision started, warm start included
    implicit_sim.restore_warm_start(world.model, saved_warm, world.data)
    return sorted(rollouts, key=lambda r: (r.rejected != "", r.score)), direction_W


def execute(world, push, direction_W, push_steps, trajectory):
    """Applies the push for real; returns the number of non-converged steps."""
    nonconverged = 0
    for _ in range(push_steps):
        report = implicit_sim.step(world.model, world.options, world.state, world.data,
                                   wrench=push_wrench(world, push, direction_W))
        nonconverged += not report.converged
        trajectory.append(world.sample())
    return nonconverged


def same_state(a, b):
    return a.t == b.t and np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)


def tilt_degrees(world):
    R_WB = world.state.pose(world.model, world.box)[1]
    return math.degrees(math.acos(min(1.0, R_WB[2, 2])))


def plan(world, arguments):
    """The decision loop. Returns the decision log and the trajectory (t, x, y, yaw)."""
    target = np.array(arguments.target, dtype=float)
    push_steps = round(arguments.decision_period / arguments.h)
    coast_steps = round(arguments.coast / arguments.h)
    pushes = candidate_pushes(arguments.quick)
    log, trajectory = [], [world.sample()]
    print(f"{len(pushes)} candidate pushes, horizon {arguments.decision_period:g} s push + {arguments.coast:g} s "
          f"coast, target ({target[0]:g}, {target[1]:g}) m")
    print(f"{'t (s)':>6} {'x (m)':>7} {'y (m)':>7} {'dist (m)':>8}  {'chosen push':<26} {'score':>6} {'lost':>4} "
          f"{'tip':>4}  example of a rejection")
    for decision in range(arguments.max_decisions):
        distance = float(np.linalg.norm(world.position() - target))
        if distance <= arguments.tolerance and world.speed() <= arguments.rest_speed:
            break
        rollouts, direction_W = decide(world, pushes, push_steps, coast_steps, target, arguments)
        best = rollouts[0]
        if best.rejected:
            raise RuntimeError(f"every candidate was rejected at t = {world.state.t:.3f} s")
        lost = [r for r in rollouts if r.rejected == "contact lost"]
        tipping = [r for r in rollouts if r.rejected == "tipping"]
        position, t = world.position(), world.state.t
        nonconverged = execute(world, best.push, direction_W, push_steps, trajectory)
        matched = same_state(world.state, best.state_after_push)
        example = next(iter((tipping + lost) if decision % 2 else (lost + tipping)), None)  # one of each, in turn
        print(f"{t:6.2f} {position[0]:7.3f} {position[1]:7.3f} {distance:8.3f}  {best.push.label():<26} "
              f"{best.score:6.3f} {len(lost):4d} {len(tipping):4d}  "
              + (f"{example.push.label()}: {example.rejected} {example.detail}" if example else ""))
        log.append({"decision": decision, "t_s": t, "x_m": position[0], "y_m": position[1], "distance_m": distance,
                    "push": best.push.label(), "force_N": best.push.force, "heading_deg": best.push.heading,
                    "height_m": best.push.height, "elevation_deg": best.push.elevation,
                    "predicted_score_m": best.score, "predicted_end_distance_m": best.end_distance,
                    "rejected_contact_lost": len(lost), "rejected_tipping": len(tipping),
                    "rejected_not_converged": sum(r.rejected == "not converged" for r in rollouts),
                    "rejected": "; ".join(f"{r.push.label()}: {r.rejected}" for r in lost + tipping),
                    "matched_rollout_bit_for_bit": matched, "nonconverged_steps": nonconverged})
    return log, trajectory


def plot(log, trajectory, arguments, path):
    trajectory = np.array(trajectory)
    target = np.array(arguments.target)
    figure, (top, distance_axis) = plt.subplots(1, 2, figsize=(11, 4.5))
    top.plot(trajectory[:, 1], trajectory[:, 2], "-", color="tab:blue", label="box centre")
    top.plot([r["x_m"] for r in log], [r["y_m"] for r in log], ".", color="tab:blue", label="decisions")
    top.plot(*target, "x", color="tab:green", ms=10, label=f"target ({arguments.tolerance * 1e3:g} mm circle)")
    top.add_patch(plt.Circle(target, arguments.tolerance, color="tab:green", alpha=0.3))
    corners_B = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]]) * HALF_EXTENTS[:2]
    for (_, x, y, yaw), style in ((trajectory[0], "--"), (trajectory[-1], "-")):
        c, s = math.cos(yaw), math.sin(yaw)
        corners_W = corners_B @ np.array([[c, s], [-s, c]]) + (x, y)
        top.plot(corners_W[:, 0], corners_W[:, 1], style, color="gray")
    top.set(xlabel="x (m)", ylabel="y (m)", title="Top view: the box's footprint at the start and end", aspect="equal")
    top.legend(fontsize=8)
    distances = np.linalg.norm(trajectory[:, 1:3] - target, axis=1)
    distance_axis.plot(trajectory[:, 0], distances, color="tab:blue")
    distance_axis.axhline(arguments.tolerance, color="tab:green", ls="--", label="tolerance")
    distance_axis.set(xlabel="t (s)", ylabel="distance to target (m)", title="Distance to the target")
    distance_axis.legend(fontsize=8)
    for axis in (top, distance_axis):
        axis.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main(argv=None):
    arguments = parse_arguments(argv)
    out = pathlib.Path(arguments.out)
    out.mkdir(parents=True, exist_ok=True)
    world = World(arguments)
    (out / "box_push.urdf").write_text(world.scene_text)
    start = time.monotonic()
    log, trajectory = plan(world, arguments)
    wall_time = time.monotonic() - start
    final_distance = float(np.linalg.norm(world.position() - np.array(arguments.target)))
    reached = final_distance <= arguments.tolerance and world.speed() <= arguments.rest_speed
    summary = {"target_m": list(arguments.target), "tolerance_m": arguments.tolerance, "reached": reached,
               "final_distance_m": final_distance, "final_speed_m_s": world.speed(),
               "final_tilt_deg": tilt_degrees(world), "t_s": world.state.t, "decisions": len(log),
               "candidates": len(candidate_pushes(arguments.quick)),
               "rejected_contact_lost": sum(r["rejected_contact_lost"] for r in log),
               "rejected_tipping": sum(r["rejected_tipping"] for r in log),
               "all_matched_bit_for_bit": all(r["matched_rollout_bit_for_bit"] for r in log),
               "nonconverged_steps": sum(r["nonconverged_steps"] for r in log),
               "h_s": arguments.h, "scheme": arguments.scheme, "wall_time_s": wall_time}
    if log:
        with open(out / "decisions.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(log[0]))
            writer.writeheader()
            writer.writerows(log)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    plot(log, trajectory, arguments, out / "path.png")
    print(f"{'reached' if reached else 'NOT reached'}: distance {final_distance * 1e3:.1f} mm (tolerance "
          f"{arguments.tolerance * 1e3:g} mm), speed {world.speed():.1e} m/s, tilt {summary['final_tilt_deg']:.1e} deg "
          f"after {len(log)} decisions ({world.state.t:.2f} s simulated, {wall_time:.1f} s wall); rejected "
          f"{summary['rejected_contact_lost']} rollouts for lost contact, {summary['rejected_tipping']} for tipping; "
          f"every real push matched its rollout bit for bit: {summary['all_matched_bit_for_bit']}")
    print(f"wrote {out / 'decisions.csv'}, {out / 'summary.json'}, {out / 'path.png'}, {out / 'box_push.urdf'}")
    assert reached, "the box did not reach the target"
    assert summary["all_matched_bit_for_bit"], "a real push differed from its rollout"
    return 0


if __name__ == "__main__":
    sys.exit(main())
