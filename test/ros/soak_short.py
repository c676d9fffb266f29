#!/usr/bin/python3
"""The soak benchmark for 60 s (bench/implicit_sim_soak.py): no error-level log message from any node, no rosbag
drop, the simulation never ahead of the wall clock, and the headless replay of the input journal ends in the live
run's state bit for bit."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rostest

DURATION_S = 60.0


class SoakShort(unittest.TestCase):
    def test_a_minute_at_real_time_logs_no_error_drops_nothing_and_replays_equal(self):
        script = os.path.join(rospkg.RosPack().get_path("implicit_sim"), "bench", "implicit_sim_soak.py")
        out = tempfile.mkdtemp(prefix="implicit_sim_soak_")
        run = subprocess.run(["/usr/bin/python3", script, "--duration", str(DURATION_S), "--sample-period", "10",
                              "--warmup", "10", "--master", "existing", "--out", out],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=400)
        print(run.stdout, flush=True)
        lines = [json.loads(line) for line in run.stdout.splitlines() if line.startswith("{")]
        samples = [line for line in lines if line["event"] == "sample"]
        summaries = [line for line in lines if line["event"] == "summary"]
        self.assertEqual(len(summaries), 1, run.stdout[-3000:])
        summary = summaries[0]
        self.assertEqual(len(samples), 6)
        self.assertEqual(summary["error_logs"], 0, summary["error_texts"])
        self.assertEqual(summary["bag_drop_warnings"], 0)
        self.assertEqual(summary["recorder_exit"], 0)
        self.assertTrue(summary["bag_closed"])
        self.assertEqual(summary["refused_steps"], 0)
        self.assertGreater(summary["commands_sent"], 0.9 * 2 * 100 * DURATION_S)  # a wrench and a joint command at 100 Hz
        self.assertGreater(summary["journal_mb"], 0.5)
        self.assertGreater(summary["bag_mb"], 0.5)
        # Real time is a ceiling: the node never runs ahead of the wall clock, even under a stream of commands (the
        # machine may be too busy to keep up, so there is no floor beyond "it ran").
        self.assertLessEqual(summary["sim_s_per_wall_s"], 1.02)
        self.assertGreater(summary["steps"], 500)
        replay = summary["replay"]
        self.assertEqual(replay["steps_done"], replay["steps"], replay["message"])
        self.assertTrue(replay["equal"], replay)
        self.assertEqual(replay["max_abs_diff"], 0.0)
        self.assertEqual(replay["bodies"], 29)  # the 24 moving bodies and the 5 fixed walls
        self.assertEqual(run.returncode, 0)


if __name__ == "__main__":
    rostest.rosrun("implicit_sim", "soak_short", SoakShort, sys.argv)
