#!/usr/bin/python3
"""Step time of implicit_sim_node before and during subscriber churn, as JSON lines on stdout.

Starts a private ROS master and the node (P3 by default, as fast as possible), records the core's wall time per step
from ~step_stats for --seconds (baseline), then again while 50 subscribe/unsubscribe cycles run on every topic the
node publishes and one subscriber never takes its messages (churn). Prints one line per phase and a comparison line.
A benchmark, not a test: timings depend on the machine and its load.

Usage (a built workspace sourced): bench/node_churn_bench.py [--scene NAME] [--seconds S] [--cycles N]
"""
import argparse
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from implicit_sim.msg import BodyStates, Contacts, StepStats

TOPICS = [("/clock", Clock), ("/tf", TFMessage), ("/diagnostics", DiagnosticArray), ("/joint_states", JointState),
          ("/implicit_sim/contacts", Contacts), ("/implicit_sim/markers", MarkerArray),
          ("/implicit_sim/body_states", BodyStates), ("/implicit_sim/step_stats", StepStats)]


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


class StepTimes:
    def __init__(self):
        self.lock = threading.Lock()
        self.samples = []  # (stamp s, wall time of the step s)

    def __call__(self, msg):
        with self.lock:
            self.samples.append((msg.header.stamp.to_sec(), msg.wall_time))

    def take(self):
        with self.lock:
            out, self.samples = self.samples, []
        return out


def summary(phase, samples, wall_s):
    times = sorted(t for _, t in samples)
    line = {"bench": "node_churn", "phase": phase, "steps": len(times), "wall_s": round(wall_s, 3)}
    if times:
        line.update(mean_step_us=round(1e6 * statistics.fmean(times), 2),
                    median_step_us=round(1e6 * times[len(times) // 2], 2),
                    p95_step_us=round(1e6 * times[int(0.95 * (len(times) - 1))], 2),
                    sim_s_per_wall_s=round((samples[-1][0] - samples[0][0]) / wall_s, 2))
    return line


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="p3_sphere_on_two_spheres")
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--cycles", type=int, default=50)
    parser.add_argument("--node", default=None, help="path of implicit_sim_node (default: from CMAKE_PREFIX_PATH)")
    args = parser.parse_args()
    candidates = [os.path.join(prefix, "lib/implicit_sim/implicit_sim_node")
                  for prefix in os.environ.get("CMAKE_PREFIX_PATH", "").split(":") if prefix]
    node = args.node or next((c for c in candidates if os.path.isfile(c)), "")
    if not os.path.isfile(node):
        sys.exit("node_churn_bench: no implicit_sim_node at '%s' (give --node PATH)" % node)
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port, ROS_HOSTNAME="localhost")
    os.environ.update(env)
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    sim = None
    try:
        time.sleep(1.5)
        sim = subprocess.Popen([node, "__name:=implicit_sim", "_scene:=" + args.scene, "_real_time_factor:=0",
                                "_publish_rate:=30"], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
        rospy.init_node("node_churn_bench", disable_signals=True)
        times = StepTimes()
        rospy.Subscriber("/implicit_sim/step_stats", StepStats, times, queue_size=1000)
        time.sleep(3.0)  # startup and the first steps
        times.take()
        start = time.monotonic()
        time.sleep(args.seconds)
        base = summary("baseline", times.take(), time.monotonic() - start)
        print(json.dumps(base), flush=True)

        stalled = rospy.Subscriber("/implicit_sim/markers", MarkerArray,
                                   lambda msg: time.sleep(3600), queue_size=1)  # never returns: its queue backs up
        start = time.monotonic()
        cycle_pause = args.seconds / max(1, args.cycles)
        for _ in range(args.cycles):
            subs = [rospy.Subscriber(topic, kind, lambda msg: None, queue_size=1) for topic, kind in TOPICS]
            time.sleep(0.5 * cycle_pause)
            for s in subs:
                s.unregister()
            time.sleep(0.5 * cycle_pause)
        churn = summary("churn", times.take(), time.monotonic() - start)
        print(json.dumps(churn), flush=True)
        stalled.unregister()
        if "mean_step_us" in base and "mean_step_us" in churn:
            print(json.dumps({"bench": "node_churn", "phase": "compare", "scene": args.scene, "cycles": args.cycles,
                              "mean_step_ratio": round(churn["mean_step_us"] / base["mean_step_us"], 3),
                              "median_step_ratio": round(churn["median_step_us"] / base["median_step_us"], 3),
                              "throughput_ratio": round(churn["sim_s_per_wall_s"] / base["sim_s_per_wall_s"], 3)}),
                  flush=True)
    finally:
        for p in (sim, master):
            if p is not None and p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
        os._exit(0)  # rospy's threads (the stalled callback) must not keep the process alive


if __name__ == "__main__":
    main()
