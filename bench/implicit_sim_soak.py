#!/usr/bin/python3
"""Soak benchmark: implicit_sim_node at real time for a long run, driven and recorded, then replayed headless.

The node runs scenes/soak_bin.urdf (20 spheres in a box and a four-joint gripper above them) at real time while this
script sends a random ~wrench_cmd and a random ~joint_command at --rate Hz and rosbag records the node's topics and the
commands. The node writes its input journal (~input_journal). JSON lines on stdout (and in OUT/soak.jsonl): one
"sample" line every --sample-period seconds (the node's RSS, step times of the window, log and drop counts so far),
then one "summary" line: RSS growth per hour after --warmup (least squares), error-level log messages, rosbag drop
warnings, step-time percentiles, and the replay: a second node replays the journal headless (~replay_journal, ~run_steps
as fast as possible) and its final state must equal the live run's bit for bit. Exit status 0 when there were no
error-level logs, no drops, the bag was closed and the replay is equal; 1 otherwise; 2 for bad arguments.

Usage (a built workspace sourced): bench/implicit_sim_soak.py [--duration S] [--out DIR] [--master own|existing] ...
bench/README.md#soak-benchmark documents it and the figures of a one-hour run.
"""
import argparse
import json
import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time

import actionlib
import rosgraph
import rospy
from rosgraph_msgs.msg import Log

from implicit_sim.msg import BodyStates, BodyWrench, JointCommand, RunStepsAction, RunStepsGoal, StepStats
from implicit_sim.srv import GetBodyState
from std_srvs.srv import Trigger

NODE = "/implicit_sim"
JOINTS = ["lift", "wrist", "left_slide", "right_slide"]
# Drive targets are drawn in these ranges (m or rad) and held for --hold seconds, with a small jitter per command. The
# lowest lift puts the finger tips 5 mm below the tops of the spheres: the fingers press and push them. Deeper, among
# the spheres, jams of fingers, spheres and walls cost seconds per step (bench/README.md#soak-benchmark).
TARGETS = {"lift": (-0.215, 0.0), "wrist": (-1.5, 1.5), "left_slide": (-0.025, 0.06), "right_slide": (-0.06, 0.025)}
JITTER = {"lift": 0.002, "wrist": 0.01, "left_slide": 0.002, "right_slide": 0.002}
STIFFNESS = {"lift": 2000.0, "wrist": 20.0, "left_slide": 500.0, "right_slide": 500.0}  # N/m or N m/rad
DAMPING = {"lift": 100.0, "wrist": 0.6, "left_slide": 10.0, "right_slide": 10.0}        # N s/m or N m s/rad
GRIPPER_LINKS = ["carriage", "palm", "left_finger", "right_finger"]
RECORDED = ["/tf", "/joint_states", NODE + "/body_states", NODE + "/step_stats", NODE + "/contacts",
            NODE + "/wrench_cmd", NODE + "/joint_command", "/diagnostics", "/rosout"]


def parse_args(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3600.0, help="wall seconds of the live run (default 3600)")
    parser.add_argument("--warmup", type=float, default=None,
                        help="seconds left out of the RSS growth fit (default: a sixth of --duration, at most 300)")
    parser.add_argument("--sample-period", type=float, default=60.0, help="seconds between sample lines (default 60)")
    parser.add_argument("--rate", type=float, default=100.0, help="commands per second of each kind (default 100)")
    parser.add_argument("--hold", type=float, default=1.5, help="seconds each drive target is held (default 1.5)")
    parser.add_argument("--seed", type=int, default=19, help="seed of the random commands (default 19)")
    parser.add_argument("--scene", default=os.path.join(here, "..", "scenes", "soak_bin.urdf"))
    parser.add_argument("--scheme", choices=["rattle", "paper"], default="rattle",
                        help="the node's ~scheme (default rattle, the node's default)")
    parser.add_argument("--tolerance", type=float, default=1e-10,
                        help="the node's ~tolerance (default 1e-10; see bench/README.md#soak-benchmark)")
    parser.add_argument("--out", default="/tmp/implicit_sim_soak", help="directory of the bag, journal and logs")
    parser.add_argument("--master", choices=["own", "existing"], default="own",
                        help="start a private ROS master (default) or use ROS_MASTER_URI's")
    parser.add_argument("--node", default=None, help="path of implicit_sim_node (default: from CMAKE_PREFIX_PATH)")
    args = parser.parse_args(argv)
    checks = [("--duration", args.duration, 1.0, 1e6), ("--sample-period", args.sample_period, 1.0, 3600.0),
              ("--rate", args.rate, 1.0, 1000.0), ("--hold", args.hold, 0.01, 3600.0)]
    for flag, value, lo, hi in checks:
        if not lo <= value <= hi:
            parser.error("%s must be in [%g, %g], got %g" % (flag, lo, hi, value))
    if args.warmup is None:
        args.warmup = min(300.0, args.duration / 6.0)
    if not 0.0 <= args.warmup < args.duration:
        parser.error("--warmup must be in [0, duration), got %g" % args.warmup)
    args.scene = os.path.abspath(args.scene)
    if not os.path.isfile(args.scene):
        parser.error("--scene: no file '%s'" % args.scene)
    candidates = [os.path.join(prefix, "lib/implicit_sim/implicit_sim_node")
                  for prefix in os.environ.get("CMAKE_PREFIX_PATH", "").split(":") if prefix]
    args.node = args.node or next((c for c in candidates if os.path.isfile(c)), "")
    if not os.path.isfile(args.node):
        parser.error("--node: no implicit_sim_node at '%s' (source the workspace or give --node PATH)" % args.node)
    return args


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def percentiles(values, points=(50, 90, 99, 99.9)):
    """Nearest-rank percentiles of values (ms) and their max, rounded to microseconds."""
    if not values:
        return {}
    ordered = sorted(values)
    out = {"p%g" % p: round(ordered[min(len(ordered) - 1, int(p / 100.0 * len(ordered)))], 3) for p in points}
    out["max"] = round(ordered[-1], 3)
    return out


def slope_per_hour(points):
    """Least-squares slope of (seconds, MB) points, in MB per hour; None with fewer than two points."""
    if len(points) < 2:
        return None
    n = float(len(points))
    mean_t = sum(t for t, _ in points) / n
    mean_m = sum(m for _, m in points) / n
    var = sum((t - mean_t) ** 2 for t, _ in points)
    cov = sum((t - mean_t) * (m - mean_m) for t, m in points)
    return round(3600.0 * cov / var, 4) if var > 0 else None


def rss_mb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS for pid %d" % pid)


class Monitor:
    """Step statistics and the error-level log messages of every node (/rosout), counted as they arrive."""

    def __init__(self):
        self.lock = threading.Lock()
        self.step_ms, self.window_ms = [], []
        self.last_step, self.nonconverged, self.refused, self.rtf = 0, 0, 0, None
        self.errors, self.warnings, self.error_texts = 0, 0, []
        rospy.Subscriber(NODE + "/step_stats", StepStats, self.on_step, queue_size=10000)
        rospy.Subscriber("/rosout", Log, self.on_log, queue_size=10000)

    def on_step(self, msg):
        with self.lock:
            self.step_ms.append(1e3 * msg.wall_time)
            self.window_ms.append(1e3 * msg.wall_time)
            self.last_step = max(self.last_step, msg.step)
            self.nonconverged += not msg.converged
            self.refused += not msg.advanced
            self.rtf = msg.real_time_factor

    def on_log(self, msg):
        if msg.name == rospy.get_name():
            return
        with self.lock:
            if msg.level >= Log.ERROR:
                self.errors += 1
                self.error_texts.append("%s: %s" % (msg.name, msg.msg))
            elif msg.level == Log.WARN:
                self.warnings += 1

    def take_window(self):
        with self.lock:
            window, self.window_ms = self.window_ms, []
            return window


class Commander(threading.Thread):
    """A random ~wrench_cmd (one sphere) and a ~joint_command (all four joints) every 1 / rate seconds."""

    def __init__(self, rate, hold, seed):
        super().__init__(daemon=True)
        self.period, self.hold, self.rng = 1.0 / rate, hold, random.Random(seed)
        self.wrench_pub = rospy.Publisher(NODE + "/wrench_cmd", BodyWrench, queue_size=100)
        self.joint_pub = rospy.Publisher(NODE + "/joint_command", JointCommand, queue_size=100)
        self.stop_event = threading.Event()
        self.sent = 0

    def random_wrench(self):
        """A random push on one link of the gripper (the drives hold against it); it holds until that link's next."""
        msg = BodyWrench(body=self.rng.choice(GRIPPER_LINKS))
        f, tau = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z = (self.rng.uniform(-2.0, 2.0) for _ in range(3))  # N
        tau.x, tau.y, tau.z = (self.rng.uniform(-0.05, 0.05) for _ in range(3))  # N m
        return msg

    def run(self):
        goals, next_goal = {}, 0.0
        start = time.monotonic()
        while not self.stop_event.is_set():
            now = time.monotonic() - start
            if now >= next_goal:
                goals = {j: self.rng.uniform(*TARGETS[j]) for j in JOINTS}
                next_goal = now + self.hold
            command = JointCommand(name=JOINTS, stiffness=[STIFFNESS[j] for j in JOINTS],
                                   damping=[DAMPING[j] for j in JOINTS],
                                   position=[goals[j] + self.rng.uniform(-JITTER[j], JITTER[j]) for j in JOINTS])
            self.wrench_pub.publish(self.random_wrench())
            self.joint_pub.publish(command)
            self.sent += 1
            self.stop_event.wait(max(0.0, start + self.sent * self.period - time.monotonic()))


def start(cmd, log_path, env):
    return subprocess.Popen(cmd, env=env, stdout=open(log_path, "w"), stderr=subprocess.STDOUT,
                            start_new_session=True)


def stop(process, timeout=15.0):
    if process is None or process.poll() is not None:
        return process.returncode if process else None
    os.killpg(process.pid, signal.SIGINT)
    try:
        return process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        return process.wait()


def wait_for_master(timeout=30.0):
    master = rosgraph.Master("/implicit_sim_soak")
    deadline = time.monotonic() + timeout
    while not master.is_online():
        if time.monotonic() > deadline:
            raise RuntimeError("the ROS master at %s did not come up in %g s" % (os.environ["ROS_MASTER_URI"], timeout))
        time.sleep(0.1)


def wait_for_closed_bag(path, timeout=60.0):
    """Whether rosbag record closed the bag (renamed PATH.active to PATH) within timeout: the recorder's C++ child
    may still be writing after the rosbag wrapper exited."""
    deadline = time.monotonic() + timeout
    while os.path.exists(path + ".active") or not os.path.exists(path):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True


def wait_for_service(name, timeout=30.0):
    rospy.wait_for_service(name, timeout=timeout)
    return rospy.ServiceProxy(name, GetBodyState if name.endswith("get_body_state") else Trigger)


def body_names():
    msg = rospy.wait_for_message(NODE + "/body_states", BodyStates, timeout=30.0)
    return [b.name for b in msg.bodies]


def final_state(names):
    """Pose and twist of every body as floats, read from the node's latest snapshot (~get_body_state)."""
    get = wait_for_service(NODE + "/get_body_state")
    state = {}
    for name in names:
        res = get(name)
        if not res.success:
            raise RuntimeError("~get_body_state %s: %s" % (name, res.message))
        pose, twist = res.state.pose, res.state.twist
        p, o, v, w = pose.position, pose.orientation, twist.linear, twist.angular
        state[name] = [p.x, p.y, p.z, o.w, o.x, o.y, o.z, v.x, v.y, v.z, w.x, w.y, w.z]
    return state


def node_command(args, extra):
    return [args.node, "__name:=implicit_sim", "_scene:=" + args.scene, "_time_step:=0.01", "_scheme:=" + args.scheme,
            "_tolerance:=%r" % args.tolerance,
            "_interactive_markers:=false"] + extra


def live_run(args, env, emit):
    """The live run: node, recorder and commands for --duration; returns (metrics, final state, steps)."""
    journal = os.path.join(args.out, "inputs.journal")
    # Paused until the first drive targets are in: otherwise the gripper falls onto the spheres before they arrive.
    node = start(node_command(args, ["_paused:=true", "_real_time_factor:=1", "_input_journal:=" + journal]),
                 os.path.join(args.out, "node.log"), env)
    recorder = None
    try:
        monitor = Monitor()
        names = body_names()
        recorder = start(["rosbag", "record", "-O", os.path.join(args.out, "soak.bag"), "--buffsize", "256"] + RECORDED,
                         os.path.join(args.out, "rosbag.log"), env)
        time.sleep(1.0)  # the recorder subscribes
        commander = Commander(args.rate, args.hold, args.seed)
        commander.start()
        time.sleep(0.5)  # the first commands reach the node
        unpaused = wait_for_service(NODE + "/unpause")()
        if not unpaused.success:
            raise RuntimeError("~unpause: " + unpaused.message)
        begin, rss_points = time.monotonic(), []
        with monitor.lock:
            first_step = monitor.last_step
        while True:
            elapsed = time.monotonic() - begin
            if elapsed >= args.duration:
                break
            time.sleep(min(args.sample_period, args.duration - elapsed))
            elapsed = time.monotonic() - begin
            rss = rss_mb(node.pid)
            rss_points.append((elapsed, rss))
            with monitor.lock:
                line = {"bench": "soak", "event": "sample", "wall_s": round(elapsed, 1), "rss_mb": round(rss, 3),
                        "steps": monitor.last_step, "rtf": monitor.rtf, "error_logs": monitor.errors,
                        "bag_drop_warnings": count_drops(args.out)}
            line["step_ms"] = percentiles(monitor.take_window())
            emit(line)
        commander.stop_event.set()
        commander.join()
        live_wall = time.monotonic() - begin
        paused = wait_for_service(NODE + "/pause")()
        if not paused.success:
            raise RuntimeError("~pause: " + paused.message)
        time.sleep(1.0)  # the last ~step_stats arrive
        state = final_state(names)
        with open(os.path.join(args.out, "live_state.json"), "w") as f:  # for a look after the run
            json.dump({"steps": monitor.last_step, "bodies": state}, f)
        recorder_exit = stop(recorder)
        bag = os.path.join(args.out, "soak.bag")
        bag_closed = wait_for_closed_bag(bag)
        stop(node)
        rospy.delete_param(NODE)  # the replaying node must not inherit ~input_journal (it would truncate the file)
        with monitor.lock:
            metrics = {"duration_s": args.duration, "warmup_s": args.warmup, "commands_sent": 2 * commander.sent,
                       "steps": monitor.last_step, "nonconverged_steps": monitor.nonconverged,
                       "refused_steps": monitor.refused, "error_logs": monitor.errors, "warn_logs": monitor.warnings,
                       "error_texts": monitor.error_texts[:10], "step_ms": percentiles(monitor.step_ms)}
        metrics["bag_drop_warnings"] = count_drops(args.out)
        metrics["recorder_exit"] = recorder_exit
        metrics["bag_closed"] = bag_closed
        metrics["bag_mb"] = round(os.path.getsize(bag if bag_closed else bag + ".active") / 2 ** 20, 2)
        metrics["journal_mb"] = round(os.path.getsize(journal) / 2 ** 20, 3)
        metrics["rss_start_mb"] = round(rss_points[0][1], 3)
        metrics["rss_end_mb"] = round(rss_points[-1][1], 3)
        metrics["rss_growth_mb_per_h"] = slope_per_hour([p for p in rss_points if p[0] >= args.warmup])
        metrics["sim_s_per_wall_s"] = round(0.01 * (metrics["steps"] - first_step) / live_wall, 4)
        return metrics, state, metrics["steps"]
    finally:
        stop(recorder)
        stop(node)


def count_drops(out):
    """rosbag record's warnings that it dropped messages (its queue overflowed)."""
    try:
        with open(os.path.join(out, "rosbag.log")) as f:
            return sum(1 for line in f if "Dropping" in line or "buffer exceeded" in line)
    except FileNotFoundError:
        return 0


def replay(args, env, names, steps):
    """A second node replays the journal headless for the live run's steps; returns (final state, wall s, result)."""
    journal = os.path.join(args.out, "inputs.journal")
    node = start(node_command(args, ["_paused:=true", "_real_time_factor:=0", "_replay_journal:=" + journal]),
                 os.path.join(args.out, "replay.log"), env)
    try:
        client = actionlib.SimpleActionClient(NODE + "/run_steps", RunStepsAction)
        if not client.wait_for_server(rospy.Duration(30.0)):
            raise RuntimeError("the replaying node's ~run_steps did not come up (see replay.log)")
        begin = time.monotonic()
        client.send_goal(RunStepsGoal(steps=steps))
        client.wait_for_result()
        result = client.get_result()
        wall = time.monotonic() - begin
        return final_state(names), wall, result
    finally:
        stop(node)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    os.makedirs(args.out, exist_ok=True)
    env = dict(os.environ, ROS_HOSTNAME=os.environ.get("ROS_HOSTNAME", "localhost"))
    master = None
    if args.master == "own":
        env["ROS_MASTER_URI"] = "http://localhost:%d" % free_port()
        master = start(["rosmaster", "--core", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]],
                       os.path.join(args.out, "master.log"), env)
    os.environ.update(env)
    wait_for_master()
    jsonl = open(os.path.join(args.out, "soak.jsonl"), "w")

    def emit(line):
        text = json.dumps(line)
        print(text, flush=True)
        jsonl.write(text + "\n")
        jsonl.flush()

    try:
        rospy.init_node("implicit_sim_soak", disable_signals=True)
        metrics, live_state, steps = live_run(args, env, emit)
        replay_state, replay_wall, result = replay(args, env, list(live_state), steps)
        diffs = [abs(a - b) for name in live_state for a, b in zip(live_state[name], replay_state[name])]
        metrics["replay"] = {"steps": steps, "steps_done": result.steps_done if result else None,
                             "message": result.message if result else "no result",
                             "bodies": len(live_state), "equal": live_state == replay_state,
                             "max_abs_diff": max(diffs) if diffs else None, "wall_s": round(replay_wall, 2)}
        ok = (metrics["error_logs"] == 0 and metrics["bag_drop_warnings"] == 0 and metrics["bag_closed"] and
              metrics["replay"]["equal"])
        emit(dict({"bench": "soak", "event": "summary", "ok": ok}, **metrics))
        return 0 if ok else 1
    finally:
        stop(master)


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # rospy's threads must not keep the process alive
