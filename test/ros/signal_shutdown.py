#!/usr/bin/python3
"""Starts COMMAND in its own process group, waits until its output contains READY (at most 15 s), sends SIGNAL to
the group 1 s later (3 s after the start when READY is -, SETTLE s later with --settle=SETTLE), waits for COMMAND to
exit and prints the end of its output, then "exit=CODE ms=MILLISECONDS" (the time from the signal to the exit).
Used by test_sim_node for the shutdown tests: a shell would start background jobs with SIGINT ignored. Only the
command's own group is signalled: roslaunch starts every node in a session of its own and must stop them itself.
Usage: signal_shutdown.py [--settle=SECONDS] SIGNAL READY|- COMMAND..."""
import os
import signal
import subprocess
import sys
import tempfile
import time


def main(argv):
    settle = None
    if argv[0].startswith("--settle="):
        settle, argv = float(argv[0][len("--settle="):]), argv[1:]
    sig, ready, command = getattr(signal, "SIG" + argv[0]), argv[1], argv[2:]
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and process.poll() is None:
            log.seek(0)
            if ready != "-" and ready.encode() in log.read():
                break
            time.sleep(0.1)
        time.sleep(settle if settle is not None else 1.0 if ready != "-" else 3.0)
        start = time.monotonic()
        os.killpg(process.pid, sig)
        try:
            code = process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            code = process.wait()
        ms = int(1000 * (time.monotonic() - start))
        log.seek(0)
        sys.stdout.write(log.read()[-4000:].decode(errors="replace"))  # the command's output, for failure messages
        print(f"\nexit={code} ms={ms}")


if __name__ == "__main__":
    main(sys.argv[1:])
