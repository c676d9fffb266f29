#!/usr/bin/python3
"""The node's API and traffic contract (doc/ros_node.md), on one cube resting on the ground (test/ros/node_contract.test:
scenes/cube_drop.urdf, real time, publish_rate 30 Hz, no /use_sim_time so the timeouts run on wall time):
- every topic, service and action of test/ros/api_contract.yaml exists with its type, and the node has no other;
- /clock and /tf keep their rates; /tf never repeats a stamp; a paused simulation sends nothing again but /clock;
- a bag of the resting cube holds at most 1/20 of the bytes per second it did before shapes were sent once;
- during a ~run_steps goal of 1e6 steps, services, /clock and feedback stay responsive; the goal cancels within 1 s;
- /diagnostics stays ERROR while a refused step holds the simulation, and OK again after ~reset; WARN, naming the
  slowest step and the ladder's rungs, while the simulation falls below half its real_time_factor;
- ~pause cuts a long step of P3 and ~delete one of the jam scene (the step undone, answered within 0.5 s);
- SIGINT stops a second node within 2 s while it runs a 1e6-step goal, and within 1.5 s in the middle of loading a
  20 000-link chain (as its startup scene and by ~load_scene), with status 0;
- every launch file declares every argument of sim.launch (with a doc) and passes them all on;
- dragging a body's interactive marker holds it where a critically damped spring predicts; releasing drops it;
- dynamic_reconfigure applies good values at once and refuses NaN, Inf and out-of-range ones, keeping the previous."""
import math
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import unittest
import xmlrpc.client

import actionlib
import dynamic_reconfigure.client
import rosbag
import rosgraph
import rospy
import rostest
import rosservice
import yaml
from xml.etree import ElementTree
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point, Pose, Vector3, Wrench
from implicit_sim.msg import BodyStates, RunStepsAction, RunStepsGoal
from implicit_sim.srv import ApplyBodyWrench, Delete, GetBodyState, LoadScene, Spawn, Step
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import InteractiveMarkerFeedback, MarkerArray

NODE = "/implicit_sim"
SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# Bytes per second of wall time of a bag of the resting cube (sim.launch's record topics, the same 8 s window) before
# shapes were sent once: measured with the node of commit f3ed9e4 (doc/ros_node.md#traffic).
BAG_RATE_BEFORE = 8.93e6


def resolve(name):
    return NODE + "/" + name[1:] if name.startswith("~") else name


def call(name, srv_type, *args, **fields):
    rospy.wait_for_service(NODE + "/" + name, timeout=10)
    return rospy.ServiceProxy(NODE + "/" + name, srv_type)(*args, **fields)


def sphere_stack_urdf(n, radius=0.05):
    """n x n x n spheres of 0.1 kg in a cubic stack on the ground, 1 mm apart (it collapses when stepped)."""
    pitch = 2 * radius + 0.001
    parts = ['<robot name="stack"><link name="world"/>']
    for i in range(n):
        for j in range(n):
            for k in range(n):
                name = "ball_%d_%d_%d" % (i, j, k)
                parts.append('<link name="%s"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" '
                             'iyy="1e-4" iyz="0" izz="1e-4"/></inertial><collision><geometry><sphere radius="%g"/>'
                             '</geometry></collision></link>' % (name, radius))
                parts.append('<joint name="%s_joint" type="floating"><parent link="world"/><child link="%s"/>'
                             '<origin xyz="%g %g %g"/></joint>' % (name, name, i * pitch + 0.0003 * k, j * pitch,
                                                                   radius + 0.001 + k * pitch))
    return "".join(parts) + "</robot>"


def revolute_chain_urdf(n):
    """A chain of n links of 1 kg on revolute joints (5 cm apart, up from the world), a 1 cm sphere on each link."""
    link = ('<link name="l%d"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>'
            '</inertial><collision><geometry><sphere radius="0.01"/></geometry></collision></link>'
            '<joint name="j%d" type="revolute"><parent link="%s"/><child link="l%d"/><origin xyz="0 0 0.05"/>'
            '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n')
    parts = ['<robot name="chain"><link name="world"/>\n']
    parts += [link % (i, i, "world" if i == 0 else "l%d" % (i - 1), i) for i in range(n)]
    return "".join(parts) + "</robot>\n"


def start_side_node(name, scene, scenes_dir, params=(), stderr=subprocess.DEVNULL):
    """A second node `name` (no leading /) on `scene`, in a session of its own. Its /clock, /tf, /tf_static,
    /diagnostics and /joint_states are remapped to /<name>_<topic>: the contract's node keeps those topics."""
    remaps = ["%s:=/%s_%s" % (topic, name, topic) for topic in ("clock", "tf", "tf_static", "diagnostics",
                                                                "joint_states")]
    return subprocess.Popen(["rosrun", "implicit_sim", "implicit_sim_node", "__name:=" + name, "_scene:=" + scene,
                             "_scenes_dir:=" + scenes_dir] + list(params) + remaps,
                            stdout=subprocess.DEVNULL, stderr=stderr, start_new_session=True)


def wait_for_registration(name, process, timeout=60):
    """Until the node `name` (its ros::start: its /rosout publisher) is known to the master."""
    master = rosgraph.Master("/node_contract")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        try:
            master.lookupNode(name)
            return
        except rosgraph.MasterError:
            time.sleep(0.02)
    ended = process.poll()
    raise AssertionError("%s %s" % (name, "ended (status %s) before it registered with the master" % ended
                                   if ended is not None else "did not register with the master in %g s" % timeout))


def stop_process(process):
    """SIGINT to the process's group; SIGKILL if it is still there 20 s later."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


class Recorder:
    """Arrival wall times (time.monotonic) and messages of one topic."""

    def __init__(self, topic, msg_type):
        self.lock = threading.Lock()
        self.items = []
        self.sub = rospy.Subscriber(topic, msg_type, self.on_message, queue_size=10000)

    def on_message(self, msg):
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def since(self, wall):
        with self.lock:
            return [m for t, m in self.items if t >= wall]

    def close(self):
        self.sub.unregister()


class NodeContract(unittest.TestCase):
    def test_1_every_topic_service_and_action_matches_the_contract(self):
        with open(os.path.join(SOURCE_DIR, "test/ros/api_contract.yaml")) as f:
            contract = yaml.safe_load(f)
        rospy.wait_for_service(NODE + "/pause", timeout=10)
        time.sleep(1.0)
        master = rosgraph.Master("/node_contract")
        publishers, subscribers, services = master.getSystemState()
        types = dict(master.getTopicTypes())
        published = {t: types.get(t) for t, nodes in publishers if NODE in nodes}
        subscribed = {t: types.get(t) for t, nodes in subscribers if NODE in nodes}
        served = {s: rosservice.get_service_type(s) for s, nodes in services if NODE in nodes}
        self.assertEqual(published, {resolve(k): v for k, v in contract["publishes"].items()})
        self.assertEqual(subscribed, {resolve(k): v for k, v in contract["subscribes"].items()})
        self.assertEqual(served, {resolve(k): v for k, v in contract["services"].items()})
        for name, action_type in contract["actions"].items():
            self.assertEqual(published[resolve(name) + "/feedback"], action_type + "ActionFeedback")
            self.assertEqual(subscribed[resolve(name) + "/goal"], action_type + "ActionGoal")

    def test_2_clock_and_tf_keep_their_rates_and_a_paused_node_repeats_nothing(self):
        self.assertTrue(call("unpause", Trigger).success)
        clock, tf = Recorder("/clock", Clock), Recorder("/tf", TFMessage)
        bodies, markers = Recorder(NODE + "/body_states", BodyStates), Recorder(NODE + "/markers", MarkerArray)
        time.sleep(1.0)
        start = time.monotonic()
        time.sleep(4.0)
        clock_hz = len(clock.since(start)) / 4.0
        tf_in = tf.since(start)
        stamps = [m.transforms[0].header.stamp.to_sec() for m in tf_in]
        print("[ INFO ] running: /clock %.1f Hz, /tf %.1f Hz" % (clock_hz, len(tf_in) / 4.0), flush=True)
        # Real time at h = 0.01 s: 100 steps/s, each a /clock (clock_rate 1000 Hz of sim time), plus 30/s repeats.
        self.assertGreaterEqual(clock_hz, 0.8 * 100)
        self.assertLessEqual(clock_hz, 1.2 * 130)
        self.assertGreaterEqual(len(tf_in) / 4.0, 0.8 * 30)
        self.assertLessEqual(len(tf_in) / 4.0, 1.2 * 30)
        self.assertEqual([b for a, b in zip(stamps, stamps[1:]) if b <= a], [], "/tf repeated a stamp")

        self.assertTrue(call("pause", Trigger).success)
        time.sleep(0.5)
        paused = time.monotonic()
        time.sleep(3.0)
        clock_paused = clock.since(paused)
        print("[ INFO ] paused: %d /clock, %d /tf, %d body_states, %d markers in 3 s"
              % (len(clock_paused), len(tf.since(paused)), len(bodies.since(paused)), len(markers.since(paused))),
              flush=True)
        self.assertGreaterEqual(len(clock_paused) / 3.0, 0.8 * 30)  # the clock stays alive, at the publish rate
        self.assertEqual(len({m.clock.to_sec() for m in clock_paused}), 1)
        self.assertEqual(tf.since(paused), [])
        self.assertEqual(bodies.since(paused), [])
        self.assertEqual(markers.since(paused), [])
        for r in (clock, tf, bodies, markers):  # rospy shares one connection per topic: a new one needs them gone
            r.close()
        time.sleep(0.5)
        # A new subscriber of a paused node still gets the current state and the shapes at once.
        self.assertEqual(len(rospy.wait_for_message(NODE + "/body_states", BodyStates, timeout=5).bodies), 2)
        shapes = rospy.wait_for_message(NODE + "/markers", MarkerArray, timeout=5)
        self.assertEqual(sum(m.ns == "shapes" and m.frame_locked for m in shapes.markers), 2)

    def test_3_a_bag_of_the_resting_cube_is_20_times_smaller(self):
        self.assertTrue(call("unpause", Trigger).success)
        time.sleep(2.0)  # the cube has landed
        with tempfile.TemporaryDirectory() as directory:
            bag = os.path.join(directory, "rest.bag")
            topics = ["/clock", "/tf", "/tf_static", NODE + "/contacts", NODE + "/markers", NODE + "/body_states",
                      NODE + "/step_stats", "/joint_states"]
            recorder = subprocess.Popen(["rosbag", "record", "-O", bag, "__name:=contract_recorder"] + topics,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
            time.sleep(2.0)  # subscriptions up
            size_start, wall_start = self.bag_size(bag), time.monotonic()
            time.sleep(8.0)
            size_end, wall_end = self.bag_size(bag), time.monotonic()
            os.killpg(recorder.pid, signal.SIGINT)
            recorder.wait(timeout=20)
            deadline = time.monotonic() + 15.0  # the wrapper can exit before its recorder renamed <bag>.active
            while not os.path.exists(bag) and time.monotonic() < deadline:
                time.sleep(0.1)
            rate = (size_end - size_start) / (wall_end - wall_start)
            with rosbag.Bag(bag) as b:
                counts = {t: i.message_count for t, i in b.get_type_and_topic_info().topics.items()}
        print("[ INFO ] resting cube bag: %.0f bytes/s (before: %.0f bytes/s, %.0fx smaller); %s"
              % (rate, BAG_RATE_BEFORE, BAG_RATE_BEFORE / max(rate, 1.0), counts), flush=True)
        self.assertLessEqual(rate, BAG_RATE_BEFORE / 20.0)
        self.assertGreater(counts.get("/tf", 0), 0)
        self.assertEqual(counts.get(NODE + "/markers", 0) >= 1, True)

    @staticmethod
    def bag_size(bag):
        for path in (bag + ".active", bag):
            if os.path.exists(path):
                return os.path.getsize(path)
        return 0

    def test_4_services_clock_and_feedback_answer_during_a_long_goal(self):
        self.assertTrue(call("pause", Trigger).success)
        client = actionlib.SimpleActionClient(NODE + "/run_steps", RunStepsAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(10)))
        feedback = []
        clock = Recorder("/clock", Clock)
        client.send_goal(RunStepsGoal(steps=1000000), feedback_cb=lambda f: feedback.append((time.monotonic(), f)))
        time.sleep(1.0)
        latencies = {}
        for name, srv_type, args in [("get_body_state", GetBodyState, ("cube",)), ("pause", Trigger, ()),
                                     ("clear_body_wrenches", Trigger, ())]:
            start = time.monotonic()
            call(name, srv_type, *args)
            latencies[name] = time.monotonic() - start
        step_refused = call("unpause", Trigger)
        start = time.monotonic()
        window = clock.since(start - 1.0)
        client.cancel_goal()
        self.assertTrue(client.wait_for_result(rospy.Duration(5)))
        cancel_s = time.monotonic() - start
        result = client.get_result()
        print("[ INFO ] during a 1e6-step goal: service latencies %s s, cancel %.3f s after %d steps, %d feedback, "
              "%d /clock in the last second" % ({k: round(v, 4) for k, v in latencies.items()}, cancel_s,
                                                 result.steps_done, len(feedback), len(window)), flush=True)
        for name, latency in latencies.items():
            self.assertLess(latency, 1.0, name)  # the job takes about 15 s
        self.assertFalse(step_refused.success)  # ~unpause is refused while a job runs
        self.assertLess(cancel_s, 1.0)
        self.assertEqual(client.get_state(), actionlib.GoalStatus.PREEMPTED)
        self.assertGreater(result.steps_done, 0)
        self.assertLess(result.steps_done, 1000000)
        self.assertGreaterEqual(len(feedback), 5)
        self.assertGreater(feedback[-1][1].steps_done, feedback[0][1].steps_done)
        self.assertGreaterEqual(len(window), 10)
        times = [m.clock.to_sec() for m in window]
        self.assertGreater(times[-1], times[0])  # simulation time moves during the goal
        clock.close()

    def test_5_diagnostics_stay_error_while_a_fault_holds_the_simulation(self):
        self.assertTrue(call("pause", Trigger).success)
        self.assertTrue(call("reset", Trigger).success)
        wrench = Wrench(force=Vector3(0, 0, 9e8), torque=Vector3(0, 0, 0))
        self.assertTrue(call("apply_body_wrench", ApplyBodyWrench, "cube", "", Point(0, 0, 0), wrench, 0.0, -1.0).success)
        self.assertTrue(call("unpause", Trigger).success)  # the first step diverges and pauses the simulation
        levels = []
        deadline = time.monotonic() + 6.0
        while time.monotonic() < deadline:
            levels.append(rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5).status[0].level)
        print("[ INFO ] diagnostics levels while the fault holds: %s" % levels, flush=True)
        self.assertGreaterEqual(len(levels), 4)
        self.assertEqual(set(levels[1:]), {2})  # ERROR in every report after the fault
        self.assertTrue(call("reset", Trigger).success)
        time.sleep(1.2)
        self.assertEqual(rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5).status[0].level, 0)

    def test_5b_diagnostics_warn_while_the_simulation_falls_behind_its_real_time_factor(self):
        # A 4 x 4 x 4 stack of spheres spawned 3 m away collapses: milliseconds a step, far behind a real_time_factor
        # of 1000 (the resting cube alone keeps that pace); ~min_real_time_fraction is 0.5.
        jam = call("spawn", Spawn, urdf=sphere_stack_urdf(4), prefix="stack/", pose=Pose(position=Point(3.0, 0.0, 0.0)))
        self.assertTrue(jam.success, jam.message)
        self.assertTrue(call("unpause", Trigger).success)
        client = dynamic_reconfigure.client.Client(NODE, timeout=10)
        client.update_configuration({"real_time_factor": 1000.0})
        try:
            time.sleep(2.2)  # the report of the second before the change holds the old pace's factor
            warned = None
            deadline = time.monotonic() + 6.0
            while time.monotonic() < deadline and warned is None:
                status = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5).status[0]
                if status.level == 1:
                    warned = status
            self.assertIsNotNone(warned, "no WARN at real_time_factor 1000")
            print("[ INFO ] %s" % warned.message, flush=True)
            self.assertIn("below 0.5 of the requested 1000 (last second: slowest step", warned.message)
            values = {kv.key: kv.value for kv in warned.values}
            for key in ("slowest_step_s", "max_iterations_per_step", "cold_restarts", "proximal_solves",
                        "smoothed_solves", "ipopt_solves", "substeps", "max_penetration_m"):
                self.assertIn(key, values)
            self.assertLess(float(values["real_time_factor"]), 500.0)
        finally:
            client.update_configuration({"real_time_factor": 1.0})
            self.assertTrue(call("delete", Delete, jam.bodies).success)
        time.sleep(2.2)  # a second at the old pace, then one at the new
        levels = [rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5).status[0].level for _ in range(2)]
        self.assertEqual(levels[-1], 0, levels)

    def test_7_dynamic_reconfigure_applies_good_values_and_refuses_bad_ones(self):
        client = dynamic_reconfigure.client.Client(NODE, timeout=10)
        before = client.get_configuration(timeout=5)
        self.assertEqual(before["publish_rate"], 30.0)
        for name, bad in [("real_time_factor", float("nan")), ("publish_rate", 5000.0), ("clock_rate", float("inf")),
                          ("tolerance", 0.5), ("max_iterations", 0), ("drag_frequency", -1.0),
                          ("force_marker_scale", float("-inf"))]:
            answer = client.update_configuration({name: bad})
            self.assertEqual(answer[name], before[name], name)  # refused: the previous value is kept
        answer = client.update_configuration({"publish_rate": 10.0, "tolerance": 1e-10, "max_iterations": 50})
        self.assertEqual((answer["publish_rate"], answer["tolerance"], answer["max_iterations"]), (10.0, 1e-10, 50))
        self.assertTrue(call("unpause", Trigger).success)
        tf = Recorder("/tf", TFMessage)
        time.sleep(0.5)
        start = time.monotonic()
        time.sleep(3.0)
        tf_hz = len(tf.since(start)) / 3.0
        tf.close()
        print("[ INFO ] /tf at publish_rate 10 Hz set live: %.1f Hz" % tf_hz, flush=True)
        self.assertGreaterEqual(tf_hz, 8.0)
        self.assertLessEqual(tf_hz, 12.0)
        client.update_configuration({"publish_rate": 30.0, "tolerance": before["tolerance"],
                                     "max_iterations": before["max_iterations"]})

    def test_8_dragging_the_interactive_marker_lifts_the_cube_and_releasing_drops_it(self):
        self.assertTrue(call("reset", Trigger).success)
        self.assertTrue(call("unpause", Trigger).success)
        time.sleep(1.5)  # landed
        rest = call("get_body_state", GetBodyState, "cube").state.pose
        feedback = rospy.Publisher(NODE + "/drag/feedback", InteractiveMarkerFeedback, queue_size=10)
        deadline = time.monotonic() + 5
        while feedback.get_num_connections() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        markers = Recorder(NODE + "/markers", MarkerArray)

        def send(event, lift):
            f = InteractiveMarkerFeedback(client_id="node_contract", marker_name="cube", control_name="move",
                                          event_type=event, mouse_point_valid=True)
            f.header.frame_id = "world"
            f.pose = Pose(position=Point(rest.position.x, rest.position.y, rest.position.z + lift),
                          orientation=rest.orientation)
            f.mouse_point = Point(rest.position.x, rest.position.y, rest.position.z)
            feedback.publish(f)

        send(InteractiveMarkerFeedback.MOUSE_DOWN, 0.0)
        for k in range(1, 11):  # the user lifts the marker by 0.3 m over 0.5 s
            send(InteractiveMarkerFeedback.POSE_UPDATE, 0.03 * k)
            time.sleep(0.05)
        time.sleep(2.0)
        held = call("get_body_state", GetBodyState, "cube").state.pose.position.z - rest.position.z
        arrows = [m for msg in markers.since(0) for m in msg.markers if m.ns == "drag" and m.action == 0]
        send(InteractiveMarkerFeedback.MOUSE_UP, 0.3)
        time.sleep(1.5)
        dropped = call("get_body_state", GetBodyState, "cube").state.pose.position.z - rest.position.z
        deleted = [m for msg in markers.since(0) for m in msg.markers if m.ns == "drag" and m.action == 2]
        markers.close()
        # The spring at 2 Hz: stiffness m (4 pi)^2, so gravity sags the hold by g / (4 pi)^2 = 0.062 m.
        sag = 9.81 / (4 * math.pi) ** 2
        print("[ INFO ] drag: held %.4f m above rest (expected %.4f), after release %.2e m; %d arrows, %d deleted"
              % (held, 0.3 - sag, dropped, len(arrows), len(deleted)), flush=True)
        self.assertAlmostEqual(held, 0.3 - sag, delta=0.01)
        self.assertLess(abs(dropped), 1e-3)
        self.assertGreater(len(arrows), 0)
        self.assertGreater(len(deleted), 0)

    def test_9_every_launch_file_declares_and_passes_every_argument_of_sim_launch(self):
        launch_dir = os.path.join(SOURCE_DIR, "launch")
        sim = ElementTree.parse(os.path.join(launch_dir, "sim.launch")).getroot()
        declared = {a.get("name") for a in sim.findall("arg") if a.get("default") is not None}
        for a in sim.findall("arg"):
            if a.get("default") is not None:
                self.assertTrue(a.get("doc"), "sim.launch: argument %s has no doc" % a.get("name"))
        for name in sorted(os.listdir(launch_dir)):
            if name == "sim.launch" or not name.endswith(".launch"):
                continue
            root = ElementTree.parse(os.path.join(launch_dir, name)).getroot()
            args = {a.get("name"): a for a in root.findall("arg")}
            self.assertEqual(declared - set(args), set(), "%s does not declare these sim.launch arguments" % name)
            self.assertTrue(all(a.get("doc") for a in args.values()), "%s: an argument without doc" % name)
            include = root.find("include")
            self.assertTrue(include.get("file").endswith("/launch/sim.launch"), name)
            self.assertEqual(include.get("pass_all_args"), "true", name)

    def test_6_sigint_stops_a_node_within_2_s_in_the_middle_of_a_long_goal(self):
        name = "/sigint_goal_node"
        node = subprocess.Popen(["rosrun", "implicit_sim", "implicit_sim_node", "__name:=" + name[1:],
                                 "_scene:=p3_sphere_on_two_spheres", "_scenes_dir:=" + SOURCE_DIR + "/scenes",
                                 "_paused:=true"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
        try:
            client = actionlib.SimpleActionClient(name + "/run_steps", RunStepsAction)
            self.assertTrue(client.wait_for_server(rospy.Duration(15)))
            client.send_goal(RunStepsGoal(steps=1000000))
            time.sleep(1.5)
            start = time.monotonic()
            os.killpg(node.pid, signal.SIGINT)
            code = node.wait(timeout=20)
            stop_s = time.monotonic() - start
        finally:
            if node.poll() is None:
                os.killpg(node.pid, signal.SIGKILL)
        print("[ INFO ] SIGINT during a 1e6-step goal: exit %d after %.3f s" % (code, stop_s), flush=True)
        self.assertEqual(code, 0)
        self.assertLess(stop_s, 2.0)

    def test_6b_a_service_cuts_a_long_step_and_the_step_is_redone(self):
        # Every Newton solve runs to its 5000 iterations (tolerance 1e-300), so one step of the P3 scene takes seconds.
        # Its own topics are remapped: the contract's node keeps /clock, /tf and /diagnostics.
        name = "/long_step_node"
        node = start_side_node(name[1:], "p3_sphere_on_two_spheres", SOURCE_DIR + "/scenes",
                               ["_tolerance:=1e-300", "_max_iterations:=5000", "_on_fault:=pause"])
        try:
            rospy.wait_for_service(name + "/pause", timeout=15)
            time.sleep(1.0)  # inside the first step
            start = time.monotonic()
            self.assertTrue(rospy.ServiceProxy(name + "/pause", Trigger)().success)
            pause_s = time.monotonic() - start
            state = rospy.ServiceProxy(name + "/get_body_state", GetBodyState)("ball")
            # The same step run whole by ~step (a job's step is cut only by a service command, none comes).
            start = time.monotonic()
            rospy.ServiceProxy(name + "/step", Step)(1)
            step_s = time.monotonic() - start
        finally:
            stop_process(node)
        print("[ INFO ] ~pause during a long step: answered in %.3f s; the step alone takes %.2f s" % (pause_s, step_s),
              flush=True)
        self.assertEqual(state.message, "t = 0 s")  # the cut step was undone: no time passed
        self.assertGreater(step_s, 3.0)  # so the pause 1 s after the start came during the first step
        self.assertLess(pause_s, 0.5)

    def test_6d_sigint_stops_a_node_within_2_5_s_in_the_middle_of_a_scene_load(self):
        # A 20 000-link revolute chain with a sphere on each link (7.5 MB) takes several seconds to load: SIGINT in the
        # middle of its load, as the startup scene (0.5 s after the node registers) and by ~load_scene of a running node
        # (1.5 s after the request), must end the node with status 0.
        scenes = tempfile.mkdtemp(prefix="implicit_sim_chain_")
        with open(os.path.join(scenes, "chain20k.urdf"), "w") as out:
            out.write(revolute_chain_urdf(20000))
        shutil.copy(os.path.join(SOURCE_DIR, "scenes", "p3_sphere_on_two_spheres.urdf"), scenes)
        times, answers = {}, []
        for case in ("startup", "load_scene"):
            name = "/sigint_load_node"
            scene = "chain20k" if case == "startup" else "p3_sphere_on_two_spheres"
            node = start_side_node(name[1:], scene, scenes, ["_paused:=true"], stderr=subprocess.PIPE)
            try:
                if case == "load_scene":
                    rospy.wait_for_service(name + "/load_scene", timeout=20)
                    proxy = rospy.ServiceProxy(name + "/load_scene", LoadScene)

                    def load():
                        try:
                            answers.append(proxy(file="chain20k").message)
                        except rospy.ServiceException:
                            pass  # the node ended before its answer was read
                    loader = threading.Thread(target=load, daemon=True)
                    loader.start()
                else:  # a signal before ros::init kills the node: on a loaded machine rosrun alone can take seconds
                    wait_for_registration(name, node)
                time.sleep(1.5 if case == "load_scene" else 0.5)
                self.assertIsNone(node.poll(), case + ": the node ended before the signal")
                start = time.monotonic()
                os.killpg(node.pid, signal.SIGINT)
                code = node.wait(timeout=20)
                times[case] = time.monotonic() - start
                err = node.stderr.read().decode()
            finally:
                if node.poll() is None:
                    os.killpg(node.pid, signal.SIGKILL)
                    node.wait()
            self.assertEqual(code, 0, "%s: exit status %s: %s" % (case, code, err[-2000:]))
            # The interruption itself is proven by the message below; the bound is for a loaded CI machine (0.3-0.4 s
            # measured idle; 1.74 s once in CI beside the sanitizer build), against 3 s and more for the load's rest.
            self.assertLess(times[case], 2.5, case)
            if case == "startup":
                self.assertIn("loading interrupted (shutdown requested)", err)
            else:  # the service answers the interruption if its answer leaves before the node ends
                loader.join(timeout=5)
                self.assertTrue(all("loading interrupted" in a for a in answers), answers)
        shutil.rmtree(scenes)
        print("[ INFO ] SIGINT during the load of a 20 000-link chain: the node exits 0 after %.3f s (startup), "
              "%.3f s (~load_scene)" % (times["startup"], times["load_scene"]), flush=True)

    def test_6e_delete_cuts_a_long_step_of_the_jam_and_the_world_goes_on_without_the_body(self):
        # The jam scene (the gripper pressed among 20 spheres) with an unreachable tolerance and a step of 0.1 s (its
        # first step then climbs the whole retry ladder in every sub-step: 11 s on an idle machine; at 0.01 s it took
        # 0.26 s once the singular direction's LU skipped zeros, too short for the probe below): ~delete of a sphere
        # the fingers press, 0.3 s into the first step, cuts it, and the world goes on without the sphere.
        name = "/long_jam_node"
        node = start_side_node(name[1:], "soak_jam", SOURCE_DIR + "/scenes",
                               ["_tolerance:=1e-300", "_max_iterations:=3000", "_time_step:=0.1", "_on_fault:=pause"])
        try:
            rospy.wait_for_service(name + "/delete", timeout=15)
            get = rospy.ServiceProxy(name + "/get_body_state", GetBodyState)
            time.sleep(0.3)
            before = get("ball_5")
            start = time.monotonic()
            deleted = rospy.ServiceProxy(name + "/delete", Delete)(["ball_5"])
            delete_s = time.monotonic() - start
            after, other = get("ball_5"), get("ball_6")
        finally:
            stop_process(node)
        print("[ INFO ] ~delete during a long step of the jam: answered in %.3f s" % delete_s, flush=True)
        self.assertEqual(before.message, "t = 0 s")  # 0.3 s after the start the first step was still running
        self.assertTrue(deleted.success, deleted.message)
        self.assertEqual(list(deleted.deleted), ["ball_5"])
        self.assertLess(delete_s, 0.5)
        self.assertFalse(after.success)  # gone from the snapshot
        # The cut step was undone (no time passed) and redone without the sphere; that redone step may already have
        # finished by this call (seen once on a loaded machine), never more than one.
        self.assertIn(other.message, ("t = 0 s", "t = 0.1 s"))

    def test_6c_after_a_master_restart_the_node_registers_again_or_exits(self):
        # A master of its own on a free port, killed and started again; the node runs against it.
        def free_port():
            with socket.socket() as sock:
                sock.bind(("127.0.0.1", 0))
                return sock.getsockname()[1]

        def start_master(port):
            return subprocess.Popen(["rosmaster", "--core", "-p", str(port)], stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, start_new_session=True)

        def lookup(uri, service):
            try:
                code, _, found = xmlrpc.client.ServerProxy(uri).lookupService("/test", service)
                return found if code == 1 else ""
            except OSError:
                return ""

        for policy in ("reregister", "exit"):
            port = free_port()
            uri = "http://127.0.0.1:%d/" % port
            env = dict(os.environ, ROS_MASTER_URI=uri)
            master = start_master(port)
            node = subprocess.Popen(["rosrun", "implicit_sim", "implicit_sim_node", "__name:=master_loss_node",
                                     "_scene:=p3_sphere_on_two_spheres", "_scenes_dir:=" + SOURCE_DIR + "/scenes",
                                     "_on_master_loss:=" + policy], env=env, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.PIPE, start_new_session=True)
            try:
                deadline = time.monotonic() + 20
                while time.monotonic() < deadline and not lookup(uri, "/master_loss_node/get_body_state"):
                    time.sleep(0.1)
                self.assertTrue(lookup(uri, "/master_loss_node/get_body_state"), policy)
                time.sleep(1.0)  # running
                stop_process(master)
                time.sleep(2.0)  # the node's checks see no master
                master = start_master(port)
                deadline = time.monotonic() + 20
                if policy == "reregister":
                    while time.monotonic() < deadline and not lookup(uri, "/master_loss_node/get_body_state"):
                        time.sleep(0.1)
                    answer = subprocess.run(["rosservice", "call", "/master_loss_node/get_body_state", "ball"], env=env,
                                            capture_output=True, text=True, timeout=20)
                    self.assertIn("success: True", answer.stdout, answer.stderr)
                    state = xmlrpc.client.ServerProxy(uri).getSystemState("/test")[2]
                    publishers = {topic for topic, nodes in state[0] if "/master_loss_node" in nodes}
                    self.assertIn("/master_loss_node/step_stats", publishers)
                    self.assertIn("/clock", publishers)
                    self.assertIsNone(node.poll())
                else:
                    code = node.wait(timeout=20)
                    self.assertEqual(code, 1)
                    self.assertIn("lost the ROS master", node.stderr.read().decode())
            finally:
                stop_process(node)
                stop_process(master)


if __name__ == "__main__":
    rospy.init_node("node_contract")
    rostest.rosrun("implicit_sim", "node_contract", NodeContract)
