#!/usr/bin/python3
"""Counts the test cases in the JUnit XML files under a directory (gtest and rostest results written by
catkin_make run_tests), prints every failure and a closing line 'tests: N passed, M failed', and exits 1 on any
failure, on a missing result file, or when no test ran."""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def why(problem):
    """The failure's message; rosunit leaves it empty and puts the traceback in the text: its last lines then."""
    message = (problem.get("message") or "").strip()
    if message:
        return message[:300]
    lines = [line for line in (problem.text or "").strip().splitlines() if line.strip()]
    return " | ".join(lines[-4:])[-600:]


def main(root):
    files = sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True))
    passed, failed = 0, 0
    for path in files:
        # gtest-*.xml: the core gtests; rosunit-*.xml: the cases of a rostest's gtest node; rostest-*.xml: one case
        # per rostest (fails when the test node crashed, timed out or reported failures); pytest-*.xml: the Python
        # API's tests.
        try:
            tree = ET.parse(path)
        except ET.ParseError as error:
            print(f"FAILED to read {path}: {error}")
            failed += 1
            continue
        for case in tree.iter("testcase"):
            problems = list(case.iter("failure")) + list(case.iter("error"))
            if problems:
                failed += 1
                print(f"FAILED {case.get('classname')}.{case.get('name')}: {why(problems[0])}")
            elif case.find("skipped") is None:
                passed += 1
    expected = ["gtest-test_core.xml", "gtest-test_batch.xml", "rostest-test_ros_sim_node_p3.xml", "rosunit-test_sim_node.xml",
                "pytest-python_api.xml"]
    for name in expected:
        if not any(os.path.basename(f) == name for f in files):
            print(f"FAILED missing result file {name} (did the test binary build and run?)")
            failed += 1
    print(f"tests: {passed} passed, {failed} failed")
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/test_results"))
