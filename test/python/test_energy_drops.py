"""No step creates energy (issue 32): seeded random drops of one part onto a plane, the five shape kinds at three
friction values, h = 0.01 and 0.005 s, both schemes (bench/energy_drops.py states the drops; doc/method.md, "The energy
guard"). Each step's rise of mechanical energy is checked here, independently of the simulator's own guard, against
the guard's allowance; no drop may end above its start energy, and every step must converge."""
import importlib.util

import pytest

from conftest import REPO

SPEC = importlib.util.spec_from_file_location("energy_drops", REPO / "bench" / "energy_drops.py")
energy_drops = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(energy_drops)

DROPS = 100
MODELS = {}


def run_drops(scheme, h):
    tally = energy_drops.Tally("drops", scheme, h)
    for i in range(DROPS):
        key = (energy_drops.KINDS[i % 5], energy_drops.MUS[(i // 5) % 3])
        if key not in MODELS:
            MODELS[key] = energy_drops.drop_scene(*key)
        model = MODELS[key]
        tally.run(model, energy_drops.make_options(scheme, h), energy_drops.drop_start(model, i, seed=7),
                  duration=2.0, tolerance=1e-9)
    return tally.row


@pytest.mark.parametrize("scheme", ["paper", "rattle"])
@pytest.mark.parametrize("h", [0.01, 0.005])
def test_random_drops_never_create_energy(scheme, h):
    row = run_drops(scheme, h)
    print(row)
    assert row["runs"] == DROPS and row["steps"] == DROPS * round(2.0 / h)
    assert row["nonconverged_steps"] == 0
    assert row["guard_violations"] == 0, f"{row['guard_violations']} steps rose beyond the guard's allowance"
    assert row["rising_steps_1pct"] == 0
    assert row["runs_above_start"] == 0
    if scheme == "paper":
        assert row["energy_fallbacks"] == 0  # the guard belongs to the RATTLE step


def test_the_allowance_is_tight_enough_to_fail():
    """A step that adds 1 % of a resting drop's weight times 1 cm is beyond the allowance: the check can fail."""
    model = MODELS.get(("box", 0.2)) or energy_drops.drop_scene("box", 0.2)
    weight = model.mass(model.moving_bodies[0]) * 9.81
    assert 0.01 * weight * 0.01 > energy_drops.guard_allowance(model, 0.0, 0.0, 0.0)
    assert 0.011 * 1.0 > energy_drops.guard_allowance(model, 1.0, 0.5, 0.0)
