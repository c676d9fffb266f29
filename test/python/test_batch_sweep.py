"""implicit_sim_batch's sweep files: the step options come from the core's options table and are checked by its range
check (doc/batch.md, "Step options"), and a sample's runner command carries them."""
import importlib.machinery
import importlib.util
import math
import xml.etree.ElementTree as ET

import pytest

import implicit_sim
from conftest import REPO, scene


def load_batch():
    path = str(REPO / "scripts" / "implicit_sim_batch")
    loader = importlib.machinery.SourceFileLoader("implicit_sim_batch", path)
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader("implicit_sim_batch", loader))
    loader.exec_module(module)
    return module


batch = load_batch()


def write_sweep(tmp_path, extra, duration=1):
    text = (f"scene: {scene('cube_drop.urdf')}\nbody: cube\nsamples: 2\nseed: 1\nclassifier: box_faces\n"
            f"stop:\n  duration: {duration}\n{extra}")
    path = tmp_path / "sweep.yaml"
    path.write_text(text)
    return str(path)


def test_the_sweep_keys_are_the_tables_rows_with_a_runner_flag():
    rows = {r["ros_param"]: r for r in implicit_sim.option_table() if r["runner_flag"]}
    keys = batch.step_option_rows()
    assert set(keys) == {"dt"} | set(rows) - {"time_step", "threads"}
    assert list(keys) == [k for k in ["dt" if p == "time_step" else p for p in rows] if k in keys]  # the table's order
    assert keys["dt"]["runner_flag"] == "--dt"


def test_given_options_reach_the_runner_in_the_tables_order(tmp_path):
    sweep = batch.load_sweep(write_sweep(tmp_path, "max_iterations: 40\nscheme: paper\ntolerance: '1e-10'\n"
                                                   "solver: newton\ndt: 0.004\n"))
    assert batch.step_option_flags(sweep) == ["--dt", "0.004", "--scheme", "paper", "--solver", "newton",
                                              "--tolerance", "1e-10", "--max-iterations", "40"]


def test_only_dt_has_a_default(tmp_path):
    sweep = batch.load_sweep(write_sweep(tmp_path, ""))
    assert batch.step_option_flags(sweep) == ["--dt", "0.01"]
    assert "scheme" not in sweep and "max_iterations" not in sweep


@pytest.mark.parametrize("line, message", [
    ("dt: 2", "dt: must be in (0, 1] s, got 2"),
    ("dt: 0", "dt: must be in (0, 1] s, got 0"),
    ("dt: true", "dt: must be (0, 1], got True"),
    ("dt: fast", "dt: expected a number, got 'fast'"),
    ("scheme: verlet", "scheme: must be paper or rattle, got 'verlet'"),
    ("scheme: 2", "scheme: must be paper or rattle, got 2"),
    ("solver: lemke", "solver: must be newton or ipopt, got 'lemke'"),
    ("tolerance: 0.5", "tolerance: must be in (0, 0.1], got 0.5"),
    ("max_iterations: 0", "max_iterations: must be an integer in [1, 100000], got 0"),
    ("max_iterations: 2.5", "max_iterations: must be an integer in [1, 100000], got 2.5"),
    ("threads: 2", "threads: unknown key"),
    ("lm_damping: 0.1", "lm_damping: unknown key"),  # a table row without a runner flag
])
def test_a_bad_option_is_refused_with_the_cores_message(tmp_path, line, message):
    with pytest.raises(batch.UsageError) as refused:
        batch.load_sweep(write_sweep(tmp_path, line + "\n"))
    assert message in str(refused.value)


def test_dt_longer_than_the_run_is_refused(tmp_path):
    with pytest.raises(batch.UsageError, match=r"dt: must be at most stop.duration \(0.2 s\), got 0.5"):
        batch.load_sweep(write_sweep(tmp_path, "dt: 0.5\n", duration=0.2))


def test_e_roll_is_written_into_every_friction_element_of_the_sample_scene(tmp_path):
    sweep = batch.load_sweep(write_sweep(tmp_path, "e_roll: 0.002\nrandomize:\n  mu: [0.3, 0.7]\n"))
    assert sweep["e_roll"] == 0.002
    params = batch.draw_parameters(sweep, 5, batch.scene_defaults(sweep["scene"], sweep["body"]))
    path = tmp_path / "sample.urdf"
    batch.write_sample_scene(sweep, params, str(path))
    model = implicit_sim.load_scene(str(path))
    assert model_pairs(model) >= 1
    for pair in range(model_pairs(model)):
        friction = model.pair_friction(pair)
        assert friction["e_roll"] == 0.002 and 0.3 <= friction["mu"] <= 0.7
    without = batch.load_sweep(write_sweep(tmp_path, ""))
    batch.write_sample_scene(without, batch.draw_parameters(without, 5, batch.scene_defaults(without["scene"], "cube")),
                             str(path))
    assert implicit_sim.load_scene(str(path)).pair_friction(0)["e_roll"] == 0.0  # the scene's own (none)


def model_pairs(model):
    """The number of pairs of a model (pair_bodies raises past the last)."""
    count = 0
    while True:
        try:
            model.pair_bodies(count)
        except (IndexError, ValueError):
            return count
        count += 1


@pytest.mark.parametrize("extra, message", [
    ("e_roll: -0.001\n", "e_roll: must be in [0, 1000] m, got -0.001"),
    ("e_roll: thick\n", "e_roll: expected a number, got 'thick'"),
])
def test_a_bad_e_roll_is_refused_naming_the_key_and_range(tmp_path, extra, message):
    with pytest.raises(batch.UsageError) as refused:
        batch.load_sweep(write_sweep(tmp_path, extra))
    assert message in str(refused.value)


def test_e_roll_of_a_pile_sweep_reaches_every_friction_of_its_generated_scene(tmp_path, runner):
    path = tmp_path / "pile.yaml"
    path.write_text("pile:\n  n: 4\n  shape: sphere\nsamples: 1\nseed: 1\ne_roll: 0.001\nstop:\n  duration: 0.1\n")
    sweep = batch.load_sweep(str(path))
    assert sweep["e_roll"] == 0.001
    out = tmp_path / "scene.urdf"
    batch.write_pile_scene(sweep, 7, runner, str(out))
    frictions = ET.parse(str(out)).getroot().find("implicit_sim").findall("friction")
    assert frictions and all(f.get("e_roll") == "0.001" for f in frictions)
    assert all(f.get("mu") == "0.5" for f in frictions)  # the generator's own friction, kept

def test_clearance_puts_the_lowest_point_of_a_cylinder_that_far_above_the_ground(tmp_path):
    """randomize.clearance replaces the drawn height: the shape's lowest point is `clearance` above z = 0 in every
    sampled orientation (checked on 3600 points of each rim (r = 0.05 m, length 0.06 m) at the loaded model's pose)."""
    path = tmp_path / "sweep.yaml"
    path.write_text(f"scene: {scene('cylinder_drop.urdf')}\nbody: can\nsamples: 8\nseed: 3\n"
                    "classifier: cylinder_faces\nstop:\n  duration: 1\n"
                    "randomize:\n  orientation: uniform\n  clearance: [0.001, 0.002]\n")
    sweep = batch.load_sweep(str(path))
    defaults = batch.scene_defaults(sweep["scene"], sweep["body"])
    for seed in range(8):
        params = batch.draw_parameters(sweep, seed, defaults)
        assert 0.001 <= params["clearance"] <= 0.002
        batch.write_sample_scene(sweep, params, str(tmp_path / "sample.urdf"))
        model = implicit_sim.load_scene(str(tmp_path / "sample.urdf"))
        can = model.find_body("can")
        p_WB, R_WB = implicit_sim.State.initial(model).pose(model, can)
        lowest = min(p_WB[2] + R_WB[2].dot([0.05 * math.cos(phi), 0.05 * math.sin(phi), side * 0.03])
                     for phi in (2 * math.pi * k / 3600 for k in range(3600)) for side in (-1, 1))
        assert abs(lowest - params["clearance"]) < 1e-6, (seed, lowest, params["clearance"])


@pytest.mark.parametrize("extra, message", [
    ("  clearance: -0.001\n", "randomize.clearance: must be in [0, 1000] m, got -0.001"),
    ("  clearance: 0.001\n", "randomize.clearance: supported for a sphere, box or cylinder collision of 'cube'"),
])
def test_a_bad_clearance_is_refused_naming_the_key(tmp_path, extra, message):
    with pytest.raises(batch.UsageError) as error:  # by the sweep's check, before any sample runs
        batch.load_sweep(write_sweep(tmp_path, "randomize:\n  orientation: uniform\n" + extra))
    assert message in str(error.value)
