"""Shared by scripts/compare_peers and scripts/scaling_curve: install MuJoCo, build the workspace, find and run the two
benchmarks (implicit_sim_bench and implicit_sim_mujoco_bench), format numbers, describe the machine."""
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OURS, MUJOCO = "implicit_sim_bench", "implicit_sim_mujoco_bench"


def die(message):
    """Exit 2 with one line on stderr, prefixed with the script's name."""
    print(f"{os.path.basename(sys.argv[0])}: {message}", file=sys.stderr)
    sys.exit(2)


def default_workspace():
    return os.environ.get("IMPLICIT_SIM_WS", "/tmp/implicit_sim_ws")


def install_mujoco():
    status = subprocess.run(["dpkg-query", "-W", "-f=${Status}", "libmujoco-dev"], capture_output=True, text=True)
    if "install ok installed" in status.stdout:
        return
    print(f"[{os.path.basename(sys.argv[0])}] installing libmujoco-dev", file=sys.stderr)
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run(sudo + ["apt-get", "update"], check=True, env=env)
    subprocess.run(sudo + ["apt-get", "-o", "DPkg::Lock::Timeout=900", "install", "-y", "--no-install-recommends",
                           "libmujoco-dev"], check=True, env=env)


def build(workspace):
    env = dict(os.environ, IMPLICIT_SIM_WS=workspace)
    script = f"source {shlex.quote(REPO)}/scripts/common.sh && install_packages && build_workspace"
    subprocess.run(["bash", "-c", script], check=True, env=env, stdout=sys.stderr)


def binary(workspace, name):
    """The path of benchmark `name` in the workspace, or None when it is not built."""
    path = os.path.join(workspace, "devel", "lib", "implicit_sim", name)
    return path if os.access(path, os.X_OK) else None


def run_bench(path, flags):
    """Runs one benchmark and returns its last JSON line as a dict; exits 2 when it fails."""
    result = subprocess.run([path] + flags, capture_output=True, text=True)
    if result.returncode != 0:
        die(f"{os.path.basename(path)} {' '.join(flags)} failed ({result.returncode}): {result.stderr.strip()}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def number(value, digits=3):
    if value is None:
        return "-"
    if value == 0:
        return "0"
    return f"{value:.{digits}g}" if abs(value) < 1e3 else f"{value:,.0f}"


def machine(mujoco_version):
    """Date, commit, host, cores and CPU, MuJoCo's version: the first words of a measurement's header."""
    commit = subprocess.run(["git", "-C", REPO, "describe", "--always", "--dirty"], capture_output=True,
                            text=True).stdout.strip()
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "?")
    return (f"Measured {datetime.date.today().isoformat()}, commit {commit}, {platform.node()}: {os.cpu_count()} cores "
            f"({cpu}), MuJoCo {mujoco_version}")
