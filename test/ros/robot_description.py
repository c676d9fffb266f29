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


if __name__ == "__main__":
    rospy.init_node("robot_description_test")
    rostest.rosrun("implicit_sim", "robot_description", RobotDescription)
