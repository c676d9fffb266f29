"""The examples (examples/*.py) in their quick modes, each as a subprocess in a temporary directory: exit status 0,
the files they write, and one physics check of their output against numbers computed here."""
import csv
import json
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
PYTHON = "/usr/bin/python3" if os.access("/usr/bin/python3", os.X_OK) else sys.executable


def run_example(name, tmp_path, *flags, expect=0):
    """Runs examples/<name>.py with --out tmp_path/out from tmp_path; returns the output directory and the process."""
    out = tmp_path / "out"
    process = subprocess.run([PYTHON, str(EXAMPLES / f"{name}.py"), "--out", str(out), *flags], cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
    assert process.returncode == expect, f"{name} exited {process.returncode}:\n{process.stdout}\n{process.stderr}"
    return out, process


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_friction_sweep_slopes_and_stop_times_match_the_closed_form(tmp_path):
    out, _ = run_example("friction_sweep", tmp_path, "--quick")
    assert (out / "friction_sweep.png").stat().st_size > 0
    rows = read_csv(out / "friction_sweep.csv")
    assert len(rows) == 4
    for row in rows:
        mu, h = float(row["mu"]), float(row["h"])
        # P2: e_r = 0.4 m, m = 1 kg, I = 0.4 kg m^2, w0 = 1.962 rad/s, g = 9.81 m/s^2.
        slope = -0.4 * mu * 1.0 * 9.81 / 0.4
        t_stop = 1.962 * 0.4 / (0.4 * mu * 1.0 * 9.81)
        assert float(row["slope_measured"]) == pytest.approx(slope, rel=1e-9)
        assert -1e-9 <= float(row["t_stop_measured"]) - t_stop <= h + 1e-9
        assert int(row["nonconverged_steps"]) == 0


def test_friction_sweep_exits_1_when_a_slope_misses_its_tolerance(tmp_path):
    _, process = run_example("friction_sweep", tmp_path, "--quick", "--slope-tolerance", "1e-30", expect=1)
    assert "FAIL mu = " in process.stderr and "slope error" in process.stderr


def test_monte_carlo_drop_counts_add_up_and_parts_rest_flat_on_a_face(tmp_path):
    samples = 20
    out, _ = run_example("monte_carlo_drop", tmp_path, "--samples", str(samples), "--seed", "3")
    assert (out / "faces.png").stat().st_size > 0
    assert (out / "part_drop.urdf").read_text().startswith("<?xml")
    summary = json.loads((out / "summary.json").read_text())
    drops = read_csv(out / "drops.csv")
    assert len(drops) == samples == summary["samples"]
    assert sum(summary["face_counts"].values()) == summary["counted"]
    assert summary["counted"] + summary["not_at_rest"] + summary["not_converged_drops"] + \
        summary["energy_rise_drops"] == samples
    assert summary["counted"] >= samples - 2  # under the default (paper) step, drops come to rest
    counted = [d for d in drops if d["outcome"] == "rest"]
    assert {face: sum(d["face"] == face for d in counted) for face in summary["face_counts"]} == summary["face_counts"]
    for drop in counted:
        assert int(drop["nonconverged_steps"]) == 0
        assert float(drop["tilt_deg"]) < 1e-3
        # At rest on a face, the centre sits at that face's half extent above the ground.
        assert abs(float(drop["centre_height_error_m"])) < 1e-9
    assert summary["nonconverged_steps"] == sum(int(d["nonconverged_steps"]) for d in drops)


def test_monte_carlo_drop_leaves_out_drops_with_non_converged_steps(tmp_path):
    # Two Newton iterations cannot solve a drop's first step (a cold start): every drop is reported, none counted.
    out, process = run_example("monte_carlo_drop", tmp_path, "--samples", "3", "--newton-max-iterations", "2",
                               expect=1)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["not_converged_drops"] == 3 and summary["counted"] == 0 and summary["nonconverged_steps"] >= 3
    assert process.stdout.count("non-converged steps, not counted") == 3
    assert all(d["outcome"] == "not_converged" for d in read_csv(out / "drops.csv"))


def test_planner_rollout_reaches_the_target_and_rejects_pushes_from_the_contacts(tmp_path):
    out, process = run_example("planner_rollout", tmp_path, "--quick")
    assert (out / "path.png").stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reached"] and summary["final_distance_m"] <= summary["tolerance_m"] == 0.01
    assert summary["final_tilt_deg"] < 1e-6  # never tipped
    assert summary["all_matched_bit_for_bit"] and summary["nonconverged_steps"] == 0
    assert summary["rejected_contact_lost"] >= 1 and summary["rejected_tipping"] >= 1
    decisions = read_csv(out / "decisions.csv")
    assert len(decisions) == summary["decisions"] >= 2
    for decision in decisions:
        assert decision["push"] not in [entry.split(":")[0] for entry in decision["rejected"].split("; ")]
    assert "reached: distance" in process.stdout
