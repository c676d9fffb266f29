#!/usr/bin/python3
"""Joint drives through the node (doc/ros_node.md#joint-drives) on the gripper scene (test/ros/node_drives.test):
- ~joint_command closes the fingers on the ball by position; the squeeze saturates at the URDF effort limit (10 N),
  which /joint_states reports (plus the scene's constant 2 N);
- a ~joint_trajectory lifts the palm 0.1 m in 0.5 s of simulation time: the ball rises with it without slipping and
  the lift ends on its target within the sag of the drive;
- bad commands are dropped whole and counted in /diagnostics;
- ~follow_trajectory (implicit_sim/FollowTrajectory): a move within its goal tolerance succeeds with feedback; a path
  tolerance the drive cannot keep aborts (PATH_TOLERANCE_VIOLATED) and the joint holds where it was; a tolerance on a
  joint the trajectory does not move is refused (INVALID_JOINTS); a cancelled goal is preempted;
- ~step_stats is throttled like /clock: 5000 steps of 1 ms at ~clock_rate 10 Hz give about 50 messages, 0.1 s apart."""
import time
import unittest

import actionlib
import dynamic_reconfigure.client
import rospy
from actionlib_msgs.msg import GoalStatus
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from implicit_sim.msg import (FollowTrajectoryAction, FollowTrajectoryGoal, FollowTrajectoryResult, JointCommand,
                              JointTolerance, StepStats)
from implicit_sim.srv import GetBodyState, Step
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

NODE = "/implicit_sim"


def call(name, srv_type, *args):
    rospy.wait_for_service(NODE + "/" + name, timeout=10)
    return rospy.ServiceProxy(NODE + "/" + name, srv_type)(*args)


def height(body):
    return call("get_body_state", GetBodyState, body).state.pose.position.z


def joints():
    msg = rospy.wait_for_message("/joint_states", JointState, timeout=5)
    return {n: (p, e) for n, p, e in zip(msg.name, msg.position, msg.effort)}


def diagnostic(key):
    time.sleep(1.1)
    msg = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5)
    return int({kv.key: kv.value for kv in msg.status[0].values}[key])


def publisher(topic, msg_type):
    pub = rospy.Publisher(NODE + "/" + topic, msg_type, queue_size=10)
    deadline = time.monotonic() + 5
    while pub.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    return pub


class NodeDrives(unittest.TestCase):
    def test_1_the_gripper_closes_by_position_and_a_trajectory_lifts_the_ball_without_slip(self):
        commands = publisher("joint_command", JointCommand)
        lift0 = joints()["lift"][0]
        commands.publish(JointCommand(name=["left_slide", "right_slide", "lift"], position=[0.01, -0.01, lift0],
                                      velocity=[], stiffness=[1e4, 1e4, 2000.0], damping=[20.0, 20.0, 60.0]))
        time.sleep(0.3)
        self.assertTrue(call("step", Step, 300).success)
        grip = joints()
        ball0, palm0 = height("ball"), height("palm")
        # Saturated: the drive's 10 N limit plus the scene's constant 2 N (left) and -2 N (right).
        self.assertAlmostEqual(grip["left_slide"][1], 12.0, delta=1e-6)
        self.assertAlmostEqual(grip["right_slide"][1], -12.0, delta=1e-6)

        client = dynamic_reconfigure.client.Client(NODE, timeout=10)
        client.update_configuration({"drive_stiffness": 2000.0, "drive_damping": 60.0})
        trajectories = publisher("joint_trajectory", JointTrajectory)
        trajectory = JointTrajectory(joint_names=["lift"])
        for k in range(1, 6):  # 0.1 m in 0.5 s, through points every 0.1 s
            trajectory.points.append(JointTrajectoryPoint(positions=[lift0 + 0.02 * k], velocities=[0.2 if k < 5 else 0.0],
                                                          time_from_start=rospy.Duration(0.1 * k)))
        trajectories.publish(trajectory)
        time.sleep(0.3)
        slip = 0.0
        for _ in range(10):
            self.assertTrue(call("step", Step, 100).success)
            slip = max(slip, abs((height("ball") - height("palm")) - (ball0 - palm0)))
        rise = height("ball") - ball0
        lift = joints()["lift"][0]
        print("[ INFO ] gripper: squeeze %.6f N, ball rose %.6f m, slip %.2e m, lift %.6f m off its target"
              % (grip["left_slide"][1], rise, slip, lift - (lift0 + 0.1)), flush=True)
        self.assertAlmostEqual(rise, 0.1, delta=1e-3)  # the drive's sag: (4.709 - 0.4 g) N / 2000 N/m = 0.4 mm
        self.assertLess(slip, 1e-6)
        self.assertAlmostEqual(lift, lift0 + 0.1, delta=1e-3)

    def test_2_bad_commands_are_dropped_whole_and_counted(self):
        commands = publisher("joint_command", JointCommand)
        trajectories = publisher("joint_trajectory", JointTrajectory)
        before = diagnostic("dropped_drive_commands")
        lift = joints()["lift"][0]
        commands.publish(JointCommand(name=["lift"], position=[float("nan")]))
        commands.publish(JointCommand(name=["no_such_joint"], position=[0.0]))
        commands.publish(JointCommand(name=["left_slide"], position=[0.5]))  # outside [-0.02, 0.02] m
        commands.publish(JointCommand(name=["lift", "left_slide"], position=[0.0]))  # lengths differ
        trajectories.publish(JointTrajectory(joint_names=["lift"], points=[JointTrajectoryPoint(
            positions=[0.1], time_from_start=rospy.Duration(-1.0))]))
        self.assertEqual(diagnostic("dropped_drive_commands") - before, 5)
        self.assertTrue(call("step", Step, 10).success)
        self.assertAlmostEqual(joints()["lift"][0], lift, delta=1e-4)  # the drives in force are unchanged


    def test_3_follow_trajectory_waits_for_its_tolerances_and_reports_a_code(self):
        client = dynamic_reconfigure.client.Client(NODE, timeout=10)
        client.update_configuration({"drive_stiffness": 2000.0, "drive_damping": 60.0})
        action = actionlib.SimpleActionClient(NODE + "/follow_trajectory", FollowTrajectoryAction)
        self.assertTrue(action.wait_for_server(rospy.Duration(10)))

        def goal(target, duration, path=0.0, at_goal=0.0, tolerance_joint="lift"):
            trajectory = JointTrajectory(joint_names=["lift"], points=[JointTrajectoryPoint(
                positions=[target], velocities=[0.0], time_from_start=rospy.Duration(duration))])
            return FollowTrajectoryGoal(trajectory=trajectory,
                                        path_tolerance=[JointTolerance(tolerance_joint, path, 0.0)],
                                        goal_tolerance=[JointTolerance(tolerance_joint, at_goal, 0.0)],
                                        goal_time_tolerance=rospy.Duration(0.5))

        def run(steps):  # step in chunks, letting the action look at the world between them
            for _ in range(steps // 50):
                self.assertTrue(call("step", Step, 50).success)
                time.sleep(0.05)

        feedback = []
        lift0 = joints()["lift"][0]
        action.send_goal(goal(lift0 - 0.05, 0.5, at_goal=0.002), feedback_cb=feedback.append)
        run(1000)
        self.assertTrue(action.wait_for_result(rospy.Duration(10)))
        self.assertEqual(action.get_state(), GoalStatus.SUCCEEDED, action.get_goal_status_text())
        self.assertEqual(action.get_result().error_code, FollowTrajectoryResult.SUCCESSFUL)
        self.assertGreater(len(feedback), 3)
        self.assertEqual(list(feedback[-1].joint_names), ["lift"])
        self.assertLess(abs(feedback[-1].error.positions[0]), 0.002)
        self.assertAlmostEqual(joints()["lift"][0], lift0 - 0.05, delta=0.002)

        lift1 = joints()["lift"][0]
        action.send_goal(goal(lift1 + 0.05, 0.2, path=1e-6))
        run(300)
        self.assertTrue(action.wait_for_result(rospy.Duration(10)))
        self.assertEqual(action.get_state(), GoalStatus.ABORTED)
        self.assertEqual(action.get_result().error_code, FollowTrajectoryResult.PATH_TOLERANCE_VIOLATED)
        stopped = joints()["lift"][0]
        self.assertLess(stopped - lift1, 0.02)  # stopped early on the way up
        run(200)
        self.assertAlmostEqual(joints()["lift"][0], stopped, delta=1e-3)  # held where it stopped

        action.send_goal(goal(lift1, 0.5, at_goal=0.01, tolerance_joint="left_slide"))
        self.assertTrue(action.wait_for_result(rospy.Duration(10)))
        self.assertEqual(action.get_result().error_code, FollowTrajectoryResult.INVALID_JOINTS)

        action.send_goal(goal(lift1 + 0.05, 5.0))
        run(100)
        action.cancel_goal()
        self.assertTrue(action.wait_for_result(rospy.Duration(10)))
        self.assertEqual(action.get_state(), GoalStatus.PREEMPTED)

    def test_4_step_stats_are_throttled_like_the_clock(self):
        client = dynamic_reconfigure.client.Client(NODE, timeout=10)
        client.update_configuration({"clock_rate": 10.0})
        stamps = []
        sub = rospy.Subscriber(NODE + "/step_stats", StepStats, lambda m: stamps.append(m.header.stamp.to_sec()))
        time.sleep(0.5)
        self.assertTrue(call("step", Step, 5000).success)  # 5 s of simulation time, as fast as possible
        time.sleep(0.5)
        sub.unregister()
        client.update_configuration({"clock_rate": 1000.0})
        gaps = [b - a for a, b in zip(stamps, stamps[1:])]
        print("[ INFO ] step_stats: %d messages over 5000 steps, gaps %.4f-%.4f s" % (len(stamps), min(gaps), max(gaps)),
              flush=True)
        self.assertGreaterEqual(len(stamps), 45)
        self.assertLessEqual(len(stamps), 51)
        self.assertGreaterEqual(min(gaps), 0.1 - 1e-6)


if __name__ == "__main__":
    rospy.init_node("node_drives")
    rostest.rosrun("implicit_sim", "node_drives", NodeDrives)
