#!/usr/bin/python3
"""Times what the tests check without a clock (doc/testing.md: speed is never asserted in a test), one JSON line each:
  {"case": "refuse", "file": ..., "wall_s": ...}   the runner refusing each malformed scene of test/data/malformed and
                                                   a 50 MB scene (the loader's size limit), process start included;
  {"case": "shutdown", "signal": "INT"|"TERM", "exit": ..., "ms": ...}   a node running as fast as it can, stopped by
                                                   the signal (test/ros/signal_shutdown.py: the time from the signal to
                                                   the exit);
then a summary line with the slowest of each and the targets: a refusal within 2 s, a shutdown within 2 s
("met": true or false). Exit status 0 unless a run could not be made (a missed target is reported, not an error).
Usage: refusal_bench.py WS        (WS: a built workspace, e.g. /tmp/implicit_sim_ws)"""
import json
import os
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGET_S = 2.0


def refusals(runner, out_dir):
    corpus = os.path.join(REPO, "test", "data", "malformed")
    files = sorted(os.path.join(corpus, f) for f in os.listdir(corpus) if f.endswith(".urdf"))
    big = os.path.join(out_dir, "fifty_megabytes.urdf")
    with open(big, "w") as f:  # a valid head, 50 MB of filler: refused by size before it is parsed
        f.write("<robot name='big'>" + "x" * (50 * 1024 * 1024 - 26) + "</robot>")
    files.append(big)
    for path in files:
        start = time.monotonic()
        result = subprocess.run([runner, "--scene", path, "--duration", "0.01", "--out", os.path.join(out_dir, "o")],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.monotonic() - start
        yield {"case": "refuse", "file": os.path.basename(path), "exit": result.returncode, "wall_s": round(wall, 4)}


def shutdowns(node):
    shutdown = os.path.join(REPO, "test", "ros", "signal_shutdown.py")
    for sig in ("INT", "TERM"):
        out = subprocess.run(["/usr/bin/python3", shutdown, sig, "contact pairs", node, "__name:=bench_" + sig.lower(),
                              "_scene:=p3_sphere_on_two_spheres", "_scenes_dir:=" + os.path.join(REPO, "scenes"),
                              "_real_time_factor:=0"], capture_output=True, text=True).stdout
        tail = out[out.rfind("exit="):].split()
        code, ms = int(tail[0].split("=")[1]), int(tail[1].split("=")[1])
        yield {"case": "shutdown", "signal": sig, "exit": code, "ms": ms}


def main(argv):
    if len(argv) != 1:
        print(__doc__.splitlines()[-1], file=sys.stderr)
        return 2
    bin_dir = os.path.join(argv[0], "devel", "lib", "implicit_sim")
    slowest_refusal, slowest_shutdown = 0.0, 0.0
    with tempfile.TemporaryDirectory() as out_dir:
        for line in refusals(os.path.join(bin_dir, "implicit_sim_run"), out_dir):
            slowest_refusal = max(slowest_refusal, line["wall_s"])
            print(json.dumps(line), flush=True)
    for line in shutdowns(os.path.join(bin_dir, "implicit_sim_node")):
        slowest_shutdown = max(slowest_shutdown, line["ms"] / 1e3)
        print(json.dumps(line), flush=True)
    print(json.dumps({"case": "summary", "slowest_refusal_s": slowest_refusal, "slowest_shutdown_s": slowest_shutdown,
                      "target_s": TARGET_S,
                      "met": slowest_refusal <= TARGET_S and slowest_shutdown <= TARGET_S}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
