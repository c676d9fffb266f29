#!/usr/bin/python3
"""Starts COMMAND in its own process group, waits until its output contains READY (or for --wait s), sends SIGNAL to
the group and prints "exit=CODE ms=MILLISECONDS" (the time from the signal to the exit). Used by test_sim_node for
the shutdown tests: a shell would start background jobs with SIGINT ignored.
Usage: signal_shutdown.py SIGNAL READY|- COMMAND..."""
import os
import signal
import subprocess
import sys
import tempfile
import time


def main(argv):
    sig, ready, command = getattr(signal, "SIG" + argv[0]), argv[1], argv[2:]
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and process.poll() is None:
            log.seek(0)
            if ready != "-" and ready.encode() in log.read():
                break
            time.sleep(0.1)
        time.sleep(1.0 if ready != "-" else 3.0)
        start = time.monotonic()
        os.killpg(process.pid, sig)
        try:
            code = process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            code = process.wait()
        print(f"exit={code} ms={int(1000 * (time.monotonic() - start))}")


if __name__ == "__main__":
    main(sys.argv[1:])
