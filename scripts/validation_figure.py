#!/usr/bin/python3
"""The coin figure of doc/validation.md: the side frequency of a thick coin against its thickness / diameter ratio.

Usage: scripts/validation_figure.py OUT.png --study RATIO:DIR[:LABEL] [--study ...]
Each --study is an implicit_sim_batch output directory (its results.jsonl, classifier cylinder_faces) of a coin with
thickness / diameter RATIO; studies with the same LABEL share a marker and a legend entry. Draws, against t/d:
the quasi-static closed form t / sqrt(t^2 + d^2); each study's side share with its Wilson 95 % interval; and the
crowd-sourced hand tosses recorded in doc/validation.md (second-hand, counts unknown, so without intervals)."""
import argparse
import json
import math
import os
from importlib.machinery import SourceFileLoader

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The Wilson interval of the batch report (scripts/implicit_sim_batch_report, a script without a .py suffix).
wilson = SourceFileLoader("implicit_sim_batch_report", os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                    "implicit_sim_batch_report")).load_module().wilson
CROWD = [(0.707 / 2.0, 0.132), (1.154 / 2.0, 0.410)]  # (t/d, edge share): doc/validation.md, "A crowd experiment"


def side_share(directory):
    with open(os.path.join(directory, "results.jsonl")) as f:
        classes = [json.loads(line)["class"] for line in f if line.strip()]
    return sum(c == "side" for c in classes), len(classes)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("--study", action="append", default=[], metavar="RATIO:DIR[:LABEL]")
    args = parser.parse_args()
    fig, axis = plt.subplots(figsize=(7, 4.5))
    ratios = [0.02 * i for i in range(1, 61)]
    axis.plot(ratios, [r / math.sqrt(1 + r * r) for r in ratios], "k-", label="quasi-static limit t / sqrt(t^2 + d^2)")
    styles = {}
    for study in args.study:
        ratio, directory, label = (study.split(":", 2) + ["simulated (this project)"])[:3]
        k, n = side_share(directory)
        lo, hi = wilson(k, n)
        first = label not in styles
        style = styles.setdefault(label, ("os^vD"[len(styles) % 5], f"C{len(styles)}"))
        axis.errorbar([float(ratio)], [k / n], yerr=[[k / n - lo], [hi - k / n]], fmt=style[0], color=style[1],
                      capsize=4, label=f"{label}, Wilson 95 %" if first else None)
        print(f"{label}: t/d = {ratio}: side {k} of {n} = {k / n:.3f}, Wilson 95 % [{lo:.3f}, {hi:.3f}]")
    axis.plot([c[0] for c in CROWD], [c[1] for c in CROWD], "r*", markersize=12,
              label="hand tosses, crowd-sourced (second-hand, counts unknown)")
    axis.set_xlabel("thickness / diameter")
    axis.set_ylabel("share resting on the side")
    axis.set_xlim(0, 1.2)
    axis.set_ylim(0, 0.8)
    axis.grid(True, alpha=0.3)
    axis.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
