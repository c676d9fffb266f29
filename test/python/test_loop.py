"""A step loop in Python: no memory that grows with the number of steps, and the GIL released while the core steps."""
import os
import signal
import subprocess
import sys
import threading
import time
import tracemalloc

import numpy as np
import pytest

import implicit_sim
from conftest import scene


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_ten_thousand_steps_allocate_no_growing_memory():
    model = implicit_sim.load_scene(scene("cube_drop.urdf"))  # the cube lands and rests: a contact at every step
    options = implicit_sim.StepperOptions()
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    wrench = np.zeros(model.nv)

    def loop(steps):
        for i in range(steps):
            report = implicit_sim.step(model, options, state, data, wrench=wrench)
            assert report.converged
            height = state.q[2]  # a view: no copy of the state
            if i % 10 == 0:
                assert data.contacts["normal_force"].sum() > -1e-9 and height > 0.0

    loop(1000)  # warm: the workspace has its size, numpy its caches
    tracemalloc.start()
    traced_before, rss_before = tracemalloc.get_traced_memory()[0], resident_bytes()
    loop(10000)
    traced_growth, rss_growth = tracemalloc.get_traced_memory()[0] - traced_before, resident_bytes() - rss_before
    tracemalloc.stop()
    print(f"10000 steps: Python heap growth {traced_growth} B, resident growth {rss_growth} B")
    assert traced_growth < 16 * 1024
    assert rss_growth < 1024 * 1024
    assert abs(state.t - 11000 * options.h) < 1e-9


def test_another_thread_runs_python_while_a_step_is_solved():
    model = implicit_sim.load_scene(scene("p1_ngon1000.urdf"))  # one pair of about 1000 unknowns: slow steps
    options = implicit_sim.StepperOptions()
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    implicit_sim.step(model, options, state, data)
    intervals, done = [], threading.Event()

    def worker():
        for _ in range(8):
            start = time.perf_counter()
            implicit_sim.step(model, options, state, data)
            intervals.append((start, time.perf_counter()))
        done.set()

    ticks = []
    thread = threading.Thread(target=worker)
    thread.start()
    while not done.is_set():
        ticks.append(time.perf_counter())  # pure Python: runs only while this thread holds the GIL
    thread.join()
    ticks = np.array(ticks)
    # For each step, the largest stretch without a tick of this thread, as a fraction of the step's length. Holding the
    # GIL through the step would make it about 1.
    fractions = []
    for start, end in intervals:
        inside = np.r_[start, ticks[(ticks > start) & (ticks < end)], end]
        fractions.append(np.diff(inside).max() / (end - start))
    print("step lengths (ms):", [round(1e3 * (e - s), 1) for s, e in intervals],
          "largest gaps:", np.round(fractions, 2))
    assert min(e - s for s, e in intervals) > 0.005
    assert np.median(fractions) < 0.5


def test_a_data_being_stepped_in_another_thread_is_refused():
    model = implicit_sim.load_scene(scene("p1_ngon1000.urdf"))
    options = implicit_sim.StepperOptions()
    state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
    implicit_sim.step(model, options, state, data)
    about_to_step, worker_errors = threading.Event(), []

    def worker():
        about_to_step.set()
        try:
            implicit_sim.step(model, options, state, data)  # 70-500 ms
        except ValueError as error:  # main's call came first (the worker was descheduled): the test retries
            worker_errors.append(error)

    refusals = []
    for _ in range(5):
        about_to_step.clear()
        thread = threading.Thread(target=worker)
        thread.start()
        about_to_step.wait()
        time.sleep(0.03)
        for call in (lambda: implicit_sim.step(model, options, implicit_sim.State.initial(model), data),
                     lambda: implicit_sim.restore_warm_start(model, implicit_sim.save_warm_start(data), data),
                     lambda: data.contacts):
            try:
                call()
            except ValueError as error:
                refusals.append(str(error))
        thread.join()
        if len(refusals) == 3:
            break
        refusals.clear()
    assert refusals == ["this Data is being stepped in another thread: give each thread a Data of its own"] * 3
    report = implicit_sim.step(model, options, state, data)  # and it is usable again afterwards
    assert report.advanced


def _unsolvable_p3():
    """P3 with a tolerance no solve reaches: its first step climbs every rung and sub-step (6-7 s on the 2-core
    machine) before it gives up; interrupting it is the point of the tests below."""
    model = implicit_sim.load_scene(scene("p3_sphere_on_two_spheres.urdf"))
    options = implicit_sim.StepperOptions()
    options.newton.tolerance = 1e-300
    return model, options, implicit_sim.State.initial(model), implicit_sim.Data(model)


def test_max_wall_interrupts_a_long_step_and_undoes_it():
    model, options, state, data = _unsolvable_p3()
    before = state.copy()
    start = time.monotonic()
    report = implicit_sim.step(model, options, state, data, max_wall=0.2)
    elapsed = time.monotonic() - start
    assert report.fault == "interrupted" and not report.advanced and not report.converged
    assert state.t == before.t
    assert np.array_equal(state.q, before.q) and np.array_equal(state.v, before.v)
    assert elapsed < 3.0, elapsed
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="max_wall must be a finite number of seconds > 0"):
            implicit_sim.step(model, options, state, data, max_wall=bad)


def test_ctrl_c_interrupts_a_step_undoes_it_and_raises_keyboard_interrupt():
    script = f"""
import sys, time
sys.path.insert(0, {os.path.dirname(os.path.dirname(implicit_sim.__file__))!r})  # the package this test imported
import implicit_sim
model = implicit_sim.load_scene({scene("p3_sphere_on_two_spheres.urdf")!r})
options = implicit_sim.StepperOptions()
options.newton.tolerance = 1e-300
state, data = implicit_sim.State.initial(model), implicit_sim.Data(model)
print("stepping", flush=True)
try:
    implicit_sim.step(model, options, state, data)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt at t =", state.t, flush=True)
"""
    process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    first = process.stdout.readline().strip()
    if first != "stepping":
        process.kill()
        pytest.fail("the stepping script failed:\n" + first + "\n" + process.communicate()[0])
    time.sleep(0.5)
    start = time.monotonic()
    process.send_signal(signal.SIGINT)
    output, _ = process.communicate(timeout=30)
    elapsed = time.monotonic() - start
    assert "KeyboardInterrupt at t = 0.0" in output, output
    assert elapsed < 3.0, elapsed
