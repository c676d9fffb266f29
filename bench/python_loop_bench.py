#!/usr/bin/python3
"""The cost of driving the core from Python: the same runs through implicit_sim.step in a Python loop and through the
C++ runner (implicit_sim_run), side by side in one process run, one JSON line per scene on stdout. `overhead_us` is
the Python loop's wall time per step minus the runner's time inside Step per step (summary.json's us_per_step);
`python_us_per_step` counts the whole loop (the call, the report object, reading state.q).

Usage (after sourcing the workspace): /usr/bin/python3 bench/python_loop_bench.py [--runner PATH] [--repeat N]"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import implicit_sim

REPO = pathlib.Path(__file__).resolve().parents[1]
CASES = [("p3_sphere_on_two_spheres.urdf", 5.0), ("cube_drop.urdf", 5.0), ("gripper_lift.urdf", 2.0)]
H = 0.01  # s


def python_loop(path, duration):
    """Wall seconds of the loop and of the time inside the core's Step (StepReport.wall_time_s)."""
    model = implicit_sim.load_scene(str(path))
    options = implicit_sim.StepperOptions()
    options.h = H
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    steps, inside = round(duration / H), 0.0
    start = time.perf_counter()
    for _ in range(steps):
        report = implicit_sim.step(model, options, state, data)
        inside += report.wall_time_s
        state.q[2]
    return time.perf_counter() - start, inside, steps


def runner_us_per_step(runner, path, duration):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([runner, "--scene", str(path), "--duration", str(duration), "--dt", str(H), "--out", out],
                       check=True, capture_output=True)
        with open(os.path.join(out, "summary.json")) as f:
            return json.load(f)["us_per_step"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runner", default=os.path.join(os.environ.get("CMAKE_PREFIX_PATH", "").split(":")[0],
                                                         "lib", "implicit_sim", "implicit_sim_run"))
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the fastest counts")
    args = parser.parse_args()
    if not os.access(args.runner, os.X_OK):
        sys.exit(f"python_loop_bench: no runner at '{args.runner}' (source devel/setup.bash or pass --runner)")
    for name, duration in CASES:
        path = REPO / "scenes" / name
        loops = [python_loop(path, duration) for _ in range(args.repeat)]
        loop_s, inside_s, steps = min(loops)
        runner_us = min(runner_us_per_step(args.runner, path, duration) for _ in range(args.repeat))
        print(json.dumps({"scene": name[:-5], "steps": steps, "python_us_per_step": round(1e6 * loop_s / steps, 2),
                          "python_step_us_per_step": round(1e6 * inside_s / steps, 2),
                          "runner_us_per_step": round(runner_us, 2),
                          "overhead_us": round(1e6 * loop_s / steps - runner_us, 2)}), flush=True)


if __name__ == "__main__":
    main()
