"""The Python API against the headless runner (bit for bit), the core's checks (ValueError, nothing changed), warm
starts, and applied wrenches and efforts against closed forms."""
import csv
import json
import math
import pathlib
import subprocess

import numpy as np
import pytest

import implicit_sim
from conftest import scene
from implicit_sim.scene import Scene, Shape


@pytest.mark.parametrize("name, duration, scheme", [
    ("p3_sphere_on_two_spheres.urdf", "5", "rattle"),  # the whole 5 s of P3
    ("p3_sphere_on_two_spheres.urdf", "1", "paper"),
    ("gripper_lift.urdf", "0.5", "rattle"),  # joints
    ("cube_drop.urdf", "1", "rattle"),
])
def test_the_trajectory_equals_the_runners_bit_for_bit(runner, tmp_path, name, duration, scheme):
    subprocess.run([runner, "--scene", scene(name), "--duration", duration, "--dt", "0.01", "--scheme", scheme,
                    "--out", str(tmp_path)], check=True, capture_output=True)
    with open(tmp_path / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    model = implicit_sim.load_scene(scene(name))
    options = implicit_sim.StepperOptions()
    options.h = 0.01
    options.scheme = scheme
    data = implicit_sim.Data(model)
    state = implicit_sim.State.initial(model)
    moving = [model.body_names[b] for b in model.moving_bodies]
    q_columns = [f"{b}.{c}" for b in moving for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]
    v_columns = [f"{b}.{c}" for b in moving for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
    assert len(rows) == round(float(duration) / 0.01) + 1
    for i, row in enumerate(rows):
        if i > 0:
            report = implicit_sim.step(model, options, state, data)
            assert report.converged
            assert report.iterations == int(row["step.iterations"])
            assert report.residual == float(row["step.residual"])
            for pair, gap, force in zip(data.contacts["pair"], data.contacts["gap"], data.contacts["normal_force"]):
                assert gap == float(row[model.pair_names[pair] + ".gap"])
                assert force == float(row[model.pair_names[pair] + ".fn"])
        assert state.t == float(row["t"])
        # The CSV writes the shortest text that reads back to the same double: equality is bit for bit.
        assert list(state.q) == [float(row[c]) for c in q_columns], f"q differs at step {i}"
        assert list(state.v) == [float(row[c]) for c in v_columns], f"v differs at step {i}"


def new_p3():
    model = implicit_sim.load_scene(scene("p3_sphere_on_two_spheres.urdf"))
    return model, implicit_sim.StepperOptions(), implicit_sim.State.initial(model), implicit_sim.Data(model)


def test_state_views_are_read_only_and_follow_the_state():
    model, options, state, data = new_p3()
    q = state.q
    with pytest.raises(ValueError):
        q[0] = 1.0
    implicit_sim.step(model, options, state, data)
    assert q[2] == state.q[2] and state.t == options.h  # a view of the state itself, not a copy


@pytest.mark.parametrize("entry, value, message", [
    ("q", lambda q: np.r_[q[:3], [2.0, 0.0, 0.0, 0.0]], "state: body 'ball' (q[3:7], its quaternion w, x, y, z) must "
     "be a unit quaternion (norm within 1e-09 of 1), got norm 2: normalize it"),
    ("q", lambda q: np.r_[[np.nan], q[1:]], "state: body 'ball' (q[0:3], its position p_WB in m) must be finite"),
    ("v", lambda v: np.r_[v[:3], [0.0, np.inf, 0.0]], "state: body 'ball' (v[3:6], its angular velocity w_WB in rad/s) "
     "must be finite"),
    ("v", lambda v: v[:5], "state: v must hold 6 values, got 5"),
    ("t", lambda t: float("nan"), "state: t must be finite, got nan"),
])
def test_a_bad_state_is_refused_with_the_cores_message_and_changes_nothing(entry, value, message):
    model, options, state, data = new_p3()
    implicit_sim.step(model, options, state, data)
    before = (state.t, state.q.copy(), state.v.copy())
    with pytest.raises(ValueError) as error:
        setattr(state, entry, value(getattr(state, entry)))
    assert str(error.value) == message
    assert state.t == before[0] and np.array_equal(state.q, before[1]) and np.array_equal(state.v, before[2])


def test_bad_options_are_refused_with_the_tables_message_and_change_nothing():
    options = implicit_sim.StepperOptions()
    for attribute, value, message in [
            ("h", 0.0, "StepperOptions.h must be in (0, 1] s, got 0"),
            ("h", float("nan"), "StepperOptions.h must be in (0, 1] s, got nan"),
            ("scheme", "euler", "StepperOptions.scheme must be paper or rattle, got 'euler'"),
            ("threads", 2.5, "StepperOptions.threads must be an integer in [0, 256], got 2.5"),
            ("h", "0.01", "StepperOptions.h must be a number in (0, 1] s, got '0.01'"),
            ("scheme", 1, "StepperOptions.scheme must be paper or rattle, got 1")]:
        with pytest.raises(ValueError) as error:
            setattr(options, attribute, value)
        assert str(error.value) == message
    with pytest.raises(ValueError, match=r"StepperOptions.newton.tolerance must be in \(0, 0.1\], got 1"):
        options.newton.tolerance = 1.0
    assert repr(options) == repr(implicit_sim.StepperOptions())


def test_every_option_of_the_table_is_an_attribute_named_as_the_cpp_field():
    options = implicit_sim.StepperOptions()
    table = implicit_sim.option_table()
    assert len(table) == 29
    for row in table:
        field = row["field"]
        owner, name = (options.newton, field[7:]) if field.startswith("newton.") else (options, field)
        assert getattr(owner, name) == row["default"], row["field"]
        setattr(owner, name, row["default"])
    options.h = 0.005
    options.scheme = "paper"
    options.newton.max_iterations = 50
    assert (options.h, options.scheme, options.newton.max_iterations) == (0.005, "paper", 50)


def test_bad_step_input_is_refused_before_the_state_changes():
    model, options, state, data = new_p3()
    implicit_sim.step(model, options, state, data)
    before = (state.t, state.q.copy(), state.v.copy())
    cases = [
        (dict(wrench=np.zeros(5)), "wrench (force then torque per moving body: N, N m) must hold 6 values, got 5"),
        (dict(wrench=np.r_[np.nan, np.zeros(5)]), "external wrench vector must hold 6 finite values (force, torque per "
         "moving body)"),
        (dict(joint_efforts=np.zeros(1)), "joint_efforts (one per joint) must hold 0 values, got 1"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError) as error:
            implicit_sim.step(model, options, state, data, **kwargs)
        assert str(error.value) == message
    other = implicit_sim.load_scene(scene("p3_sphere_on_two_spheres.urdf"))
    with pytest.raises(ValueError, match="Data was made for another Model"):
        implicit_sim.step(model, options, state, implicit_sim.Data(other))
    assert state.t == before[0] and np.array_equal(state.q, before[1]) and np.array_equal(state.v, before[2])


def test_bad_scenes_are_refused_with_the_loaders_message(tmp_path):
    with pytest.raises(ValueError, match="no_such_scene.urdf"):
        implicit_sim.load_scene(str(tmp_path / "no_such_scene.urdf"))
    text = open(scene("p3_sphere_on_two_spheres.urdf")).read().replace('mu="', 'mu="-')
    with pytest.raises(ValueError, match="mu"):
        implicit_sim.load_scene_string(text)


def run(model, options, state, data, steps, **kwargs):
    """The states after each of `steps` steps, as (t, q, v) copies."""
    out = []
    for _ in range(steps):
        report = implicit_sim.step(model, options, state, data, **kwargs)
        assert report.converged
        out.append((state.t, state.q.copy(), state.v.copy()))
    return out


def same(a, b):
    return len(a) == len(b) and all(ta == tb and np.array_equal(qa, qb) and np.array_equal(va, vb)
                                    for (ta, qa, va), (tb, qb, vb) in zip(a, b))


@pytest.mark.parametrize("name, steps", [("p3_sphere_on_two_spheres.urdf", 150), ("gripper_lift.urdf", 60)])
def test_saved_state_and_warm_start_continue_bit_identically(name, steps):
    model = implicit_sim.load_scene(scene(name))
    options = implicit_sim.StepperOptions()
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    run(model, options, state, data, steps)
    saved_state, saved_warm = state.copy(), implicit_sim.save_warm_start(data)
    assert saved_warm.valid
    first = run(model, options, state, data, steps)
    state.assign(saved_state)
    fresh = implicit_sim.Data(model)  # a new workspace: only the saved warm start carries over
    implicit_sim.restore_warm_start(model, saved_warm, fresh)
    assert same(run(model, options, state, fresh, steps), first)
    # Without the warm start the step starts cold: another solve path, so the check above can fail.
    state.assign(saved_state)
    implicit_sim.clear_warm_start(fresh)
    assert not fresh.has_warm_start
    run(model, options, state, fresh, 1)


def cube_scene(force=None):
    """A 1 kg cube (edge 1 m, rotations locked) resting on the floor, mu = 0.5, optionally with a constant applied
    force in the scene."""
    scene = Scene("cube")
    scene.friction(mu=0.5, e_t=1, e_o=1, e_r=0.01)
    scene.body("cube", locked="rx ry rz", force=force)
    scene.halfspace("floor")
    scene.link("cube", 1, ("0.1667", "0.1667", "0.1667"), collision=Shape.box((1, 1, 1)))
    scene.floating("cube", xyz=(0, 0, 0.5))
    return scene.urdf()


def test_a_wrench_given_per_step_acts_as_the_same_force_in_the_scene():
    force = (4.0, 1.0, 0.0)  # |f_t| = 4.12 N < mu m g = 4.905 N: the cube sticks
    fixed = implicit_sim.load_scene_string(cube_scene(force))
    model = implicit_sim.load_scene_string(cube_scene())
    options = implicit_sim.StepperOptions()
    with_scene = run(fixed, options, implicit_sim.State.initial(fixed), implicit_sim.Data(fixed), 50)
    state = implicit_sim.State.initial(model)
    # Not bit for bit: the scene's constant force also enters the solver's row scaling (Model::ForceScale).
    with_python = run(model, options, state, implicit_sim.Data(model), 50, wrench=np.r_[force, 0.0, 0.0, 0.0])
    for (t_a, q_a, v_a), (t_b, q_b, v_b) in zip(with_scene, with_python):
        assert t_a == t_b and np.abs(q_a - q_b).max() < 1e-12 and np.abs(v_a - v_b).max() < 1e-12
    assert np.linalg.norm(state.q[:2]) < 1e-9  # static friction holds it
    run(model, options, state, implicit_sim.Data(model), 10, wrench=np.r_[force, 0.0, 0.0, 0.0] * 2)
    assert state.v[0] > 0.1  # twice the force (8.2 N > 4.905 N) makes it slide: the check above can fail


def test_a_pushed_cube_slides_with_the_closed_form_acceleration():
    model = implicit_sim.load_scene_string(cube_scene())
    options = implicit_sim.StepperOptions()
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    push = 10.0  # N along x; kinetic friction mu m g = 4.905 N: a = 5.095 m/s^2
    run(model, options, state, data, 100, wrench=np.array([push, 0, 0, 0, 0, 0.0]))
    assert state.v[0] == pytest.approx((push - 0.5 * 9.81) * 1.0, rel=1e-9)
    contacts = data.contacts
    (row,) = np.flatnonzero(contacts["normal_force"] > 0)
    assert contacts["normal_force"][row] == pytest.approx(9.81, rel=1e-9)
    assert contacts["friction_force_W"][row] == pytest.approx([-0.5 * 9.81, 0, 0], abs=1e-9)
    assert contacts["slip_speed"][row] == pytest.approx(state.v[0], rel=1e-9)
    assert abs(contacts["gap"][row]) < 1e-9
    assert np.allclose(contacts["p_WA1"][row] - contacts["p_WA2"][row], contacts["gap"][row] * contacts["n_W"][row])


def test_a_joint_effort_holding_the_pendulum_against_gravity_keeps_it_still():
    model = implicit_sim.load_scene(scene("pendulum.urdf"))  # m = 1 kg at L = 1 m, released at 5 degrees
    options = implicit_sim.StepperOptions()
    theta0 = implicit_sim.joint_position(model, implicit_sim.State.initial(model), 0)
    hold = np.array([9.81 * math.sin(theta0)])  # N m about +y: the gravity torque is -m g L sin(theta)
    state = implicit_sim.State.initial(model)
    run(model, options, state, implicit_sim.Data(model), 100, joint_efforts=hold)
    assert abs(implicit_sim.joint_position(model, state, 0) - theta0) < 1e-9
    free = implicit_sim.State.initial(model)
    run(model, options, free, implicit_sim.Data(model), 100)
    assert abs(implicit_sim.joint_position(model, free, 0) - theta0) > 1e-2  # without it, it swings


def test_wrench_at_point_adds_the_moment_about_the_centre_of_mass():
    model = implicit_sim.load_scene_string(cube_scene())
    state = implicit_sim.State.initial(model)
    body = model.find_body("cube")
    wrench = implicit_sim.wrench_at_point(model, state, body, p_WP=[0.5, 0, 0.5], f_W=[0, 0, 2.0])
    assert list(wrench) == [0, 0, 2.0, 0, -1.0, 0]  # (0.5, 0, 0) x (0, 0, 2) = (0, -1, 0) N m
    with pytest.raises(ValueError):
        implicit_sim.wrench_at_point(model, state, model.find_body("floor"), p_WP=[0, 0, 0], f_W=[1, 0, 0])


def test_the_model_reads_as_the_scene_says():
    model = implicit_sim.load_scene(scene("p3_sphere_on_two_spheres.urdf"))
    assert model.body_names == ["ball", "sphere_a", "sphere_b"] and model.moving_bodies == [0]
    assert (model.nq, model.nv, model.num_bodies, model.num_moving) == (7, 6, 3, 1)
    assert model.pair_names == ["ball-sphere_a", "ball-sphere_b"]
    ball, sphere_b = model.find_body("ball"), model.find_body("sphere_b")
    assert model.find_body("nothing") == -1 and model.is_fixed(sphere_b) and not model.is_fixed(ball)
    assert model.velocity_slot(ball) == 0 and model.velocity_slot(sphere_b) == -1
    assert model.mass(ball) == 1.0 and model.shape_type(ball) == "sphere"
    assert model.pair_bodies(model.pair_index(sphere_b, ball)) == (ball, sphere_b)
    assert model.pair_friction(0) == {"mu": 0.2, "e_t": 1.0, "e_o": 1.0, "e_r": 0.3, "e_roll": 0.0}
    assert list(model.gravity) == [0.0, 0.0, 0.0]  # P3: a constant force instead of gravity
    assert np.array_equal(model.inertia(ball), 0.4 * np.eye(3))
    vertices, triangles = implicit_sim.surface_mesh(model, sphere_b, resolution=8)
    p_WB, R_WB = implicit_sim.State.initial(model).pose(model, sphere_b)
    assert np.allclose(np.linalg.norm(vertices, axis=1), 9.0, atol=1e-9)  # sphere_b: r = 9 m
    assert triangles.shape == (2 * 8 * 16, 3) and triangles.max() == len(vertices) - 1
    for call in (lambda: model.mass(3), lambda: model.pair_bodies(2), lambda: model.pair_index(-1, 0),
                 lambda: implicit_sim.surface_mesh(model, 0, resolution=1)):
        with pytest.raises(ValueError):
            call()


def test_a_step_case_written_from_python_replays_as_recorded(runner, tmp_path):
    """write_step_case: a RATTLE step of a dropped box, saved before the step, replays bit for bit in implicit_sim_replay
    (its reversal counts included); a URDF of another scene is refused before anything is written."""
    box = Scene("case_box")
    box.friction(mu=0.5)
    box.halfspace("ground")
    box.link("box", mass=0.3, collision=Shape.box((0.1, 0.07, 0.05)))
    box.floating("box", xyz=(0, 0, 0.06))
    urdf = box.urdf()
    model = implicit_sim.load_scene_string(urdf, name="case_box")
    state, data, options = implicit_sim.State.initial(model), implicit_sim.Data(model), implicit_sim.StepperOptions()
    for _ in range(30):
        implicit_sim.step(model, options, state, data)
    before, warm = state.copy(), implicit_sim.save_warm_start(data)
    report = implicit_sim.step(model, options, state, data)
    path = tmp_path / "box.case"
    implicit_sim.write_step_case(str(path), "box_step30", "test_bindings.py", urdf, "case_box", options, before, warm,
                                 data, report)
    assert "\nvelocity_reversals 1\n" in path.read_text()
    replay = pathlib.Path(runner).with_name("implicit_sim_replay")
    lines = subprocess.run([str(replay), str(path)], check=True, capture_output=True, text=True).stdout.splitlines()
    result = json.loads(lines[0])
    assert result["same_as_recorded"] and result["iterations"] == report.iterations
    other = Scene("other")
    other.halfspace("ground")
    for name in ("a", "b"):
        other.link(name, mass=0.3, collision=Shape.box((0.1, 0.07, 0.05)))
        other.floating(name, xyz=(0, 0, 0.06 if name == "a" else 0.3))
    other = other.urdf()
    with pytest.raises(ValueError, match="nq"):
        implicit_sim.write_step_case(str(tmp_path / "bad.case"), "bad", "test", other, "other", options, before, warm,
                                     data, report)
    assert not (tmp_path / "bad.case").exists()
