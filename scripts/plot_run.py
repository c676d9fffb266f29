#!/usr/bin/python3
"""Plots a headless run of implicit_sim_run: what the simulator did, per body and per contact.

Usage: plot_run.py RUN_DIR [--out DIR] [--svg]
Reads RUN_DIR/trajectory.csv and RUN_DIR/summary.json and writes, into DIR (default RUN_DIR/plots):
  body_<B>.png       linear velocity (m/s) and angular velocity (rad/s), world frame, of moving body B
  contact_<P>.png    per contact pair P: gap (m); normal force and friction magnitude with the mu * normal force
                     bound (N); torsional moment (N m); slip speed (m/s)
  energy.png         kinetic, potential and total energy (J)
With --svg each figure is written as SVG too. Prints the files written. Needs Debian's python3-matplotlib."""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_run(run_dir):
    with open(os.path.join(run_dir, "trajectory.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError("trajectory.csv has no rows")
    columns = {key: [float(r[key]) for r in rows] for key in rows[0]}
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    return columns, summary


def names_with(columns, suffix):
    return [key[: -len(suffix)] for key in columns if key.endswith(suffix)]


def save(fig, out_dir, name, svg, written):
    fig.tight_layout()
    for ext in ["png"] + (["svg"] if svg else []):
        path = os.path.join(out_dir, name + "." + ext)
        fig.savefig(path, dpi=110)
        written.append(path)
    plt.close(fig)


def plot_body(columns, body, title):
    t = columns["t"]
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for axis, (kind, unit) in zip(axes, [("v", "m/s"), ("w", "rad/s")]):
        for c in "xyz":
            axis.plot(t, columns[f"{body}.{kind}{c}"], label=f"{kind}_{c}")
        axis.set_ylabel(f"{'linear' if kind == 'v' else 'angular'} velocity ({unit})")
        axis.grid(True, alpha=0.3)
        axis.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    axes[0].set_title(f"{title}: body {body} (world frame)")
    return fig


def plot_contact(columns, pair, mu, title):
    t = columns["t"][1:]  # forces are unknown at t = 0
    col = {k: columns[f"{pair}.{k}"][1:] for k in ("gap", "fn", "ft", "mr", "slip")}
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    axes[0].plot(t, col["gap"], color="k")
    axes[0].set_ylabel("gap (m)")
    axes[1].plot(t, col["fn"], label="normal force")
    axes[1].plot(t, col["ft"], label="friction magnitude")
    if mu is not None:
        axes[1].plot(t, [mu * f for f in col["fn"]], "--", label=f"mu * normal force (mu = {mu:g})")
    axes[1].set_ylabel("force (N)")
    axes[1].legend(loc="best", fontsize=8)
    axes[2].plot(t, col["mr"], color="tab:purple")
    axes[2].set_ylabel("torsional moment (N m)")
    axes[3].plot(t, col["slip"], color="tab:red")
    axes[3].set_ylabel("slip speed (m/s)")
    axes[3].set_xlabel("t (s)")
    for axis in axes:
        axis.grid(True, alpha=0.3)
    axes[0].set_title(f"{title}: contact {pair}")
    return fig


def plot_energy(columns, title):
    t = columns["t"]
    kinetic, potential = columns["energy.kinetic"], columns["energy.potential"]
    fig, axis = plt.subplots(figsize=(8, 4))
    axis.plot(t, kinetic, label="kinetic")
    axis.plot(t, potential, label="potential (zero at the world origin)")
    axis.plot(t, [k + p for k, p in zip(kinetic, potential)], label="total", color="k")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("energy (J)")
    axis.set_title(f"{title}: energy")
    axis.grid(True, alpha=0.3)
    axis.legend(loc="best", fontsize=8)
    return fig


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir")
    parser.add_argument("--out", help="output directory (default RUN_DIR/plots)")
    parser.add_argument("--svg", action="store_true", help="also write SVG")
    args = parser.parse_args(argv)
    try:
        columns, summary = read_run(args.run_dir)
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as error:
        print(f"plot_run.py: cannot read the run in '{args.run_dir}': {error}", file=sys.stderr)
        return 2
    out_dir = args.out or os.path.join(args.run_dir, "plots")
    os.makedirs(out_dir, exist_ok=True)
    title = f"{summary.get('scene', 'scene')}, h = {summary.get('h', float('nan')):g} s"
    mu_of = {p["name"]: p["mu"] for p in summary.get("pairs", [])}
    written = []
    for body in names_with(columns, ".vx"):
        save(plot_body(columns, body, title), out_dir, f"body_{body}", args.svg, written)
    for pair in names_with(columns, ".fn"):
        save(plot_contact(columns, pair, mu_of.get(pair), title), out_dir, f"contact_{pair}", args.svg, written)
    if "energy.kinetic" in columns:
        save(plot_energy(columns, title), out_dir, "energy", args.svg, written)
    for path in written:
        print(path)
    return 0 if written else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
