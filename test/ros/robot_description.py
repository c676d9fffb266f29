#!/usr/bin/python3
"""robot_description and robot_state_publisher with the simulator (doc/ros_node.md#robot-urdfs), on the gripper scene:
robot_description is the scene's jointed part (palm and fingers, no free ball, no <implicit_sim>); the finger links
come on /tf from robot_state_publisher (parent -> child, fed by /joint_states) and the ball from the simulator."""
import time
import unittest

import rospy
import rostest
import tf2_ros
import yaml
from geometry_msgs.msg import Pose

from implicit_sim.srv import Spawn

# A one-joint arm with a frame link (tool0) on its moving link, as vendors ship them: root 'base' welded to the world.
ARM = """<robot name="arm"><link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
<link name="upper"><inertial><origin xyz="0 0 0.25"/><mass value="1"/><inertia ixx="0.02" iyy="0.02" izz="0.001"
 ixy="0" ixz="0" iyz="0"/></inertial><collision><origin xyz="0 0 0.25"/><geometry><box size="0.04 0.04 0.4"/>
 </geometry></collision></link>
<joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/>
 <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
<link name="tool0"/><joint name="tool_joint" type="fixed"><parent link="upper"/><child link="tool0"/>
 <origin xyz="0 0 0.5" rpy="0 0 1.5707963267948966"/></joint></robot>"""


class RobotDescription(unittest.TestCase):
    def test_robot_state_publisher_publishes_the_jointed_links_and_the_node_the_free_ball(self):
        description = rospy.get_param("/robot_description")
        for link in ("palm", "left_finger", "right_finger"):
            self.assertIn('name="%s"' % link, description)
        self.assertNotIn('name="ball"', description)
        self.assertNotIn("<implicit_sim", description)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        for frame in ("left_finger", "right_finger", "ball"):
            self.assertTrue(buffer.can_transform("world", frame, rospy.Time(0), rospy.Duration(15)), frame)
        time.sleep(1.0)
        frames = yaml.safe_load(buffer.all_frames_as_yaml())
        authority = {name: info["broadcaster"] for name, info in frames.items()}
        print("[ INFO ] tf authorities: %s" % authority, flush=True)
        self.assertEqual(authority["left_finger"], "/robot_state_publisher")
        self.assertEqual(authority["right_finger"], "/robot_state_publisher")
        self.assertEqual(authority["ball"], "/implicit_sim")
        self.assertEqual(authority["palm"], "/robot_state_publisher")  # on the prismatic joint 'lift' to world

    def test_spawned_robots_links_and_frames_come_from_the_node(self):
        """robot_state_publisher read robot_description once: a robot spawned later has its links, and its frame
        links (tool0), on /tf from the node, while the scene's links stay with robot_state_publisher."""
        rospy.wait_for_service("/implicit_sim/spawn", 15)
        pose = Pose()
        pose.position.x = 2.0
        pose.orientation.w = 1.0
        answer = rospy.ServiceProxy("/implicit_sim/spawn", Spawn)(
            urdf=ARM, prefix="arm2_", pose=pose, joint_names=["shoulder"], joint_positions=[0.3])
        self.assertTrue(answer.success, answer.message)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        for frame in ("arm2_upper", "arm2_tool0", "left_finger"):
            self.assertTrue(buffer.can_transform("world", frame, rospy.Time(0), rospy.Duration(15)), frame)
        time.sleep(1.0)
        frames = yaml.safe_load(buffer.all_frames_as_yaml())
        authority = {name: info["broadcaster"] for name, info in frames.items()}
        print("[ INFO ] tf authorities after the spawn: %s" % authority, flush=True)
        self.assertEqual(authority["arm2_upper"], "/implicit_sim")
        self.assertEqual(authority["arm2_tool0"], "/implicit_sim")
        self.assertEqual(authority["left_finger"], "/robot_state_publisher")
        # tool0 sits 0.5 m up the upper arm, turned a quarter about z, whatever the arm's swing.
        upper_tool = buffer.lookup_transform("arm2_upper", "arm2_tool0", rospy.Time(0), rospy.Duration(5)).transform
        self.assertAlmostEqual(upper_tool.translation.x, 0.0, places=6)
        self.assertAlmostEqual(upper_tool.translation.y, 0.0, places=6)
        self.assertAlmostEqual(upper_tool.translation.z, 0.5, places=6)
        self.assertAlmostEqual(abs(upper_tool.rotation.z), 2 ** -0.5, places=6)


if __name__ == "__main__":
    rospy.init_node("robot_description_test")
    rostest.rosrun("implicit_sim", "robot_description", RobotDescription)
