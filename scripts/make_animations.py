#!/usr/bin/python3
"""Renders the README's animations from real runs of the simulator (the Python bindings, stepping in Python):
  p3         scenes/p3_sphere_on_two_spheres.urdf: P3, a sphere rolling and sliding off two fixed spheres (5 s)
  ellipsoid  scenes/ellipsoid_rolling.urdf: an ellipsoid rolling end over end on the ground (4 s)
  pile       scenes/pile_drop.urdf: 30 parts dropped into a box (2 s, played at half speed)
writing OUTDIR/p3.gif, OUTDIR/ellipsoid_rolling.gif, OUTDIR/pile.gif (each checked to be under 2 MB). For each run it
prints the steps, whether every step converged, the largest penetration (max over steps of -gap of the contacts),
and the wall times of stepping and rendering.

Usage: source $WS/devel/setup.bash; /usr/bin/python3 scripts/make_animations.py OUTDIR [--only NAME]...
       [--frames N] [--duration T] [--width PX]
Exit status: 0 written; 1 a step did not converge or was refused, or a GIF is over 2 MB; 2 bad arguments or no
bindings. Units: m, s."""
import argparse
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

try:
    import implicit_sim as isim
    from implicit_sim import animation
except ImportError as error:
    sys.exit(f"make_animations: cannot import the implicit_sim bindings ({error}): build the workspace and "
             "source $WS/devel/setup.bash first")

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAX_BYTES = 2_000_000  # the README's limit per GIF
SHAPE_COLOURS = {"sphere": 0, "ellipsoid": 1, "superellipsoid": 2}  # moving bodies: index into MOVING_COLOURS


@dataclass
class Clip:
    scene: str            # file in scenes/
    gif: str              # output name
    duration: float       # simulated time (s)
    h: float              # time step (s)
    frames: int           # frames, evenly spaced in time from t = 0 to t = duration
    speed: float          # playback speed over real time
    resolution: tuple     # surface_mesh resolution (latitudes) of the moving and of the fixed bodies
    view: dict = field(default_factory=dict)  # animation.View fields
    aspect: float = 0.75  # height / width


CLIPS = {
    "p3": Clip("p3_sphere_on_two_spheres.urdf", "p3.gif", 5.0, 0.01, 101, 1.0, (16, 24),
               dict(elev_deg=40.0, azim_deg=-75.0, lower=(-5.0, -2.0, -1.5), upper=(14.0, 14.0, 11.0))),
    "ellipsoid": Clip("ellipsoid_rolling.urdf", "ellipsoid_rolling.gif", 4.0, 0.01, 81, 1.0, (20, 20),
                      dict(elev_deg=30.0, azim_deg=-60.0, tile=0.2, margin=0.1), aspect=0.6),
    "pile": Clip("pile_drop.urdf", "pile.gif", 2.0, 0.01, 81, 0.5, (8, 8),
                 dict(elev_deg=35.0, azim_deg=-60.0, tile=0.1, lower=(-0.42, -0.42, 0.0), upper=(0.42, 0.42, 0.68),
                      plane_box=((-0.4, -0.4, 0.0), (0.4, 0.4, 0.3)))),
}


def bodies_of(model, resolution):
    """animation.Body per body of the model: a half-space as its plane, every other shape as its surface mesh
    (resolution: latitudes for the moving bodies, for the fixed ones)."""
    bodies = []
    for b, name in enumerate(model.body_names):
        fixed = model.is_fixed(b)
        vertices, triangles = isim.surface_mesh(model, b, resolution=resolution[fixed])
        if fixed:
            colour = animation.FIXED_COLOURS[sum(map(model.is_fixed, range(b))) % 2]
        else:
            colour = animation.MOVING_COLOURS[SHAPE_COLOURS.get(model.shape_type(b), 3)]
        if model.shape_type(b) == "halfspace":  # a square in the plane, counter-clockwise seen from outside
            a, c, d = vertices[triangles[0]]
            normal = np.cross(c - a, d - a)
            bodies.append(animation.Body(name, fixed, plane_point=vertices.mean(axis=0),
                                         plane_normal=normal / np.linalg.norm(normal), colour=animation.PLANE_COLOUR))
        else:
            bodies.append(animation.Body(name, fixed, vertices, triangles, colour=colour))
    return bodies


def simulate(model, h, steps, frame_steps):
    """Steps the scene from its initial state; returns the Motion at frame_steps and the run's health."""
    options = isim.StepperOptions()
    options.h = h
    data, state = isim.Data(model), isim.State.initial(model)
    n, record = model.num_bodies, set(frame_steps)
    times, positions, rotations = [], [], []
    health = dict(steps=0, nonconverged=0, min_gap=np.inf, fault="none")
    start = time.perf_counter()
    for k in range(steps + 1):
        if k in record:
            poses = [state.pose(model, b) for b in range(n)]
            times.append(state.t)
            positions.append([p for p, _ in poses])
            rotations.append([R for _, R in poses])
        if k == steps:
            break
        report = isim.step(model, options, state, data)
        health["steps"] += 1
        health["nonconverged"] += not report.converged
        gaps = data.contacts["gap"]
        if len(gaps):
            health["min_gap"] = min(health["min_gap"], float(np.min(gaps)))
        if not report.advanced:
            health["fault"] = f"{report.fault} at t = {state.t:.3f} s: {report.fault_detail}"
            break
    health["wall_s"] = time.perf_counter() - start
    return animation.Motion(np.array(times), np.array(positions), np.array(rotations)), health


def make_clip(name, clip, out_dir, args):
    duration = args.duration if args.duration else clip.duration
    frames = args.frames if args.frames else clip.frames
    steps = int(round(duration / clip.h))
    frame_steps = np.unique(np.round(np.linspace(0, steps, frames)).astype(int))
    model = isim.load_scene(os.path.join(REPO, "scenes", clip.scene))
    motion, health = simulate(model, clip.h, steps, frame_steps)
    width = args.width or 480
    view = animation.View(width_px=width, height_px=int(round(width * clip.aspect / 2)) * 2, speed=clip.speed,
                          **{k: (np.array(v) if k in ("lower", "upper") else v) for k, v in clip.view.items()})
    fps = (len(frame_steps) - 1) / duration * clip.speed if len(frame_steps) > 1 else 1.0
    path = os.path.join(out_dir, clip.gif)
    start = time.perf_counter()
    written, size = animation.write_gif(animation.frames(bodies_of(model, clip.resolution), motion, view), path,
                                        fps)
    render_s = time.perf_counter() - start
    penetration = max(0.0, -health["min_gap"]) if np.isfinite(health["min_gap"]) else 0.0
    converged = "all converged" if health["nonconverged"] == 0 else f"{health['nonconverged']} NOT converged"
    print(f"{name}: {health['steps']} steps of {clip.h:g} s ({converged}), max penetration {penetration:.3g} m, "
          f"stepping {health['wall_s']:.1f} s; {written} frames at {fps:.3g} fps ({clip.speed:g}x real time), "
          f"{view.width_px}x{view.height_px} px, rendering {render_s:.1f} s; {path}: {size / 1e6:.2f} MB")
    ok = health["nonconverged"] == 0 and health["fault"] == "none"
    if health["nonconverged"] > 0:
        print(f"{name}: {health['nonconverged']} steps not converged")
    if health["fault"] != "none":
        print(f"{name}: a step was refused ({health['fault']})")
    if size > MAX_BYTES:
        print(f"{name}: {path} is {size} bytes, over the limit of {MAX_BYTES} bytes")
        ok = False
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outdir")
    parser.add_argument("--only", action="append", choices=sorted(CLIPS), help="this clip only (repeatable)")
    parser.add_argument("--frames", type=int, help="frames per clip (default: the clip's, 81-101)")
    parser.add_argument("--duration", type=float, help="simulated time per clip (s; default: the clip's)")
    parser.add_argument("--width", type=int, help="picture width (px; default 480)")
    args = parser.parse_args()
    if (args.frames is not None and args.frames < 1) or (args.width is not None and not 16 <= args.width <= 2000):
        parser.error("--frames must be >= 1 and --width in [16, 2000]")
    os.makedirs(args.outdir, exist_ok=True)
    start, ok = time.perf_counter(), True
    for name in args.only or list(CLIPS):
        ok = make_clip(name, CLIPS[name], args.outdir, args) and ok
    print(f"make_animations: {time.perf_counter() - start:.1f} s in all; {'ok' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
