"""implicit_sim.scene: the scene builder the examples, scripts/make_scenes.py and these tests write URDF with."""
import math
import subprocess
import sys

import numpy as np
import pytest

import implicit_sim
from conftest import REPO, SCENES
from implicit_sim.scene import Scene, Shape, text


def test_make_scenes_writes_the_committed_scenes(tmp_path):
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_scenes.py"), "--out", str(tmp_path)], check=True)
    written = sorted(p.name for p in tmp_path.iterdir())
    assert len(written) == 12
    for name in written:
        assert (tmp_path / name).read_text() == (SCENES / name).read_text(), f"scenes/{name} is not make_scenes' output"


def test_values_are_written_as_given_or_in_their_shortest_exact_form():
    assert text("0.250833") == "0.250833"
    assert text(1.0) == "1" and text(3) == "3" and text(np.int64(-2)) == "-2"
    assert text(0.1) == "0.1" and float(text(1 / 3)) == 1 / 3
    assert text((0, 0, -9.81)) == "0 0 -9.81" and text(np.array([0.5, 1.25])) == "0.5 1.25"
    for bad in (float("nan"), math.inf, True, None):
        with pytest.raises(ValueError):
            text(bad)


def drop_scene():
    scene = Scene("drop", comment="a test scene")
    scene.friction(mu=0.3, e_t=1, e_o=1, e_r=0.02)
    scene.friction(link1="box", link2="ground", mu=0.7)
    scene.halfspace("ground")
    scene.link("ball", 2.0, (0.008, 0.008, 0.008), visual=Shape.sphere(0.1), collision=Shape.sphere(0.1))
    scene.floating("ball", xyz=(0, 0, 0.5))
    scene.body("ball", velocity=(1, 0, 0), angular_velocity=(0, 0, 2))
    scene.link("egg", 0.5, collision=Shape.ellipsoid((0.2, 0.1, 0.05)))  # inertia of the solid from its mass
    scene.floating("egg", xyz=(1, 0, 0.5), rpy=(0, 0, 0.3))
    scene.link("box", 1.5, collision=Shape.box((0.2, 0.4, 0.6)))
    scene.floating("box", xyz=(-1, 0, 0.5))
    return scene


def test_a_built_scene_loads_with_its_masses_inertias_shapes_and_friction():
    model = implicit_sim.load_scene_string(drop_scene().urdf(), name="drop")
    ball, egg, box, ground = (model.find_body(n) for n in ("ball", "egg", "box", "ground"))
    assert model.is_fixed(ground) and model.shape_type(ground) == "halfspace"
    assert model.mass(ball) == 2.0 and np.allclose(model.inertia(ball), np.diag([0.008] * 3), rtol=0, atol=0)
    a, b, c = 0.2, 0.1, 0.05  # the solid ellipsoid: I_xx = m (b^2 + c^2) / 5, ...
    assert model.shape_type(egg) == "ellipsoid" and model.mass(egg) == 0.5
    assert np.allclose(np.diag(model.inertia(egg)), 0.5 / 5 * np.array([b * b + c * c, a * a + c * c, a * a + b * b]))
    x, y, z = 0.2, 0.4, 0.6  # the solid box: I_xx = m (y^2 + z^2) / 12, ...
    assert np.allclose(np.diag(model.inertia(box)), 1.5 / 12 * np.array([y * y + z * z, x * x + z * z, x * x + y * y]))
    assert model.pair_friction(model.pair_index(box, ground))["mu"] == 0.7
    assert model.pair_friction(model.pair_index(ball, ground)) == dict(mu=0.3, e_t=1.0, e_o=1.0, e_r=0.02, e_roll=0.0)
    state = implicit_sim.State.initial(model)
    slot = model.velocity_slot(ball)
    assert list(state.v[6 * slot:6 * slot + 6]) == [1, 0, 0, 0, 0, 2]
    assert list(state.q[7 * slot:7 * slot + 3]) == [0, 0, 0.5]


def test_joints_with_limits_and_a_start_load_as_written():
    scene = Scene("arm")
    scene.link("base", collision=Shape.box((0.1, 0.1, 0.1)))
    scene.fixed("base")
    scene.link("upper", 1, (0.01, 0.01, 0.001), com=(0, 0, 0.2),
               collision=Shape.cylinder(0.03, 0.4).at(xyz=(0, 0, 0.2)))
    scene.joint("shoulder", "revolute", "base", "upper", xyz=(0, 0, 0.05), axis=(1, 0, 0),
                limit=dict(lower=-1.5, upper=1.5, effort=20, velocity=3))
    scene.joint_start("shoulder", position=0.25)
    model = implicit_sim.load_scene_string(scene.urdf())
    shoulder = model.find_joint("shoulder")
    assert model.joint_type(shoulder) == "revolute" and model.joint_limits(shoulder) == (-1.5, 1.5)
    assert implicit_sim.joint_position(model, implicit_sim.State.initial(model), shoulder) == pytest.approx(0.25)


def test_bad_input_is_refused_naming_what_is_wrong():
    with pytest.raises(ValueError, match="'--'"):
        Scene("x", comment="a -- b")
    with pytest.raises(ValueError, match="link 'a': an inertia needs a mass"):
        Scene("x").link("a", inertia=(1, 1, 1))
    with pytest.raises(ValueError, match="link 'a': a mass without an inertia needs a collision shape"):
        Scene("x").link("a", mass=1)
    with pytest.raises(ValueError, match="finite"):
        Scene("x").link("a", 1, (1, 1, float("nan")))
    scene = Scene("x")
    scene.link("a", 1, collision=Shape.sphere(-0.1))  # the builder writes it; the loader refuses it
    scene.floating("a")
    with pytest.raises(ValueError, match="radius"):
        implicit_sim.load_scene_string(scene.urdf())


def test_names_and_comments_are_escaped_for_xml():
    scene = Scene("odd", comment="x < y & z")
    scene.link('ball "a" & <b>', 1, collision=Shape.sphere(0.1))
    scene.floating('ball "a" & <b>')
    urdf = scene.urdf()
    assert 'name="ball &quot;a&quot; &amp; &lt;b&gt;"' in urdf
    assert 'ball "a" & <b>' in implicit_sim.load_scene_string(urdf).body_names


def test_rolling_resistance_is_read_and_reported_and_stops_a_rolling_ball():
    scene = Scene("roll", comment="a ball rolling on the ground with rolling resistance")
    scene.friction(mu=0.5, e_t=1, e_o=1, e_r=0.01, e_roll=0.005)
    scene.halfspace("ground")
    scene.link("ball", 1.0, collision=Shape.sphere(0.1))
    scene.floating("ball", xyz=(0, 0, 0.1))
    scene.body("ball", velocity=(0.3, 0, 0), angular_velocity=(0, 3, 0))  # rolling without slip
    model = implicit_sim.load_scene_string(scene.urdf(), name="roll")
    ball, ground = model.find_body("ball"), model.find_body("ground")
    assert model.pair_friction(model.pair_index(ball, ground))["e_roll"] == 0.005
    options, state, data = implicit_sim.StepperOptions(), implicit_sim.State.initial(model), implicit_sim.Data(model)
    slot = model.velocity_slot(ball)
    for _ in range(10):
        assert implicit_sim.step(model, options, state, data).converged
    moment, normal = data.contacts["rolling_moment_W"][0], data.contacts["normal_force"][0]
    w = state.v[slot + 3:slot + 6]
    assert moment[1] < 0 < w[1]  # against the rolling
    assert np.linalg.norm(moment) <= 0.5 * 0.005 * normal * (1 + 1e-9)
    assert np.linalg.norm(moment) > 0.9 * 0.5 * 0.005 * normal  # nearly all of the ellipsoid: it rolls, barely slides
    for _ in range(250):  # about 1.7 s to stop from 3 rad/s (test_rolling_resistance.cpp's closed form)
        assert implicit_sim.step(model, options, state, data).converged
    assert np.abs(state.v[slot:slot + 6]).max() < 1e-9
