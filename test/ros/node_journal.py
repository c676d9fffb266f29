#!/usr/bin/python3
"""The node's replay of an input journal (doc/ros_node.md#the-input-journal), on the cube scene, paused and stepped:
test/data/journals/cube_push_then_marker.journal pushes the cube with 1 N along x before steps 0 and 1 and marks a
~set_body_state before step 2. The node applies the pushes before those steps (the cube's velocity is exactly
2 h F / m) and stops before step 2 with one ERROR naming the input, paused, ~step answering success false."""
import io
import os
import struct
import sys
import time
import unittest

import rospkg
import rospy
import rostest
from rosgraph_msgs.msg import Log

from implicit_sim.msg import BodyWrench
from implicit_sim.srv import GetBodyState, Step

NODE = "/implicit_sim"
H = 0.01          # s, the launch file's time_step
FORCE_N = 1.0     # the journal's push; the cube's mass is 1 kg
JOURNAL = "test/data/journals/cube_push_then_marker.journal"


def journal_bytes():
    """The journal as the format defines it: the header line, then (uint64 step, uint8 kind, uint32 size, bytes)."""
    out = io.BytesIO()
    out.write(b"implicit_sim input journal 1\n")
    push = BodyWrench(body="cube")
    push.wrench.force.x = FORCE_N
    records = [(0, 1, push), (1, 1, push), (2, 255, b"~set_body_state")]
    for step, kind, payload in records:
        if not isinstance(payload, bytes):
            buffer = io.BytesIO()
            payload.serialize(buffer)
            payload = buffer.getvalue()
        out.write(struct.pack("<QBI", step, kind, len(payload)) + payload)
    return out.getvalue()


class NodeJournal(unittest.TestCase):
    def test_the_file_is_the_documented_format(self):
        path = os.path.join(rospkg.RosPack().get_path("implicit_sim"), JOURNAL)
        with open(path, "rb") as f:
            self.assertEqual(f.read(), journal_bytes())

    def test_the_pushes_are_replayed_before_their_steps_and_the_marker_stops_the_replay(self):
        errors = []
        rospy.Subscriber("/rosout", Log, lambda m: errors.append(m.msg) if m.level >= Log.ERROR else None)
        rospy.wait_for_service(NODE + "/step", timeout=20)
        step = rospy.ServiceProxy(NODE + "/step", Step)
        get = rospy.ServiceProxy(NODE + "/get_body_state", GetBodyState)
        res = step(2)
        self.assertTrue(res.success, res.message)
        v_x = get("cube").state.twist.linear.x
        self.assertAlmostEqual(v_x, 2 * H * FORCE_N / 1.0, delta=1e-15)
        res = step(5)
        self.assertFalse(res.success)
        self.assertIn("stopped after 0 steps: the journal's input ~set_body_state before step 2 cannot be replayed",
                      res.message)
        self.assertAlmostEqual(res.sim_time, 2 * H, delta=1e-12)
        self.assertEqual(get("cube").state.twist.linear.x, v_x)  # no step was taken
        deadline = time.time() + 5
        while not any("replay stops" in e for e in errors) and time.time() < deadline:
            time.sleep(0.1)
        self.assertTrue(any("replay stops" in e and "~set_body_state" in e for e in errors), errors)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--write-journal":  # regenerates the committed file
        with open(sys.argv[2], "wb") as f:
            f.write(journal_bytes())
        sys.exit(0)
    rospy.init_node("node_journal_test")
    rostest.rosrun("implicit_sim", "node_journal", NodeJournal, sys.argv)
