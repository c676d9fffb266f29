"""Shared fixtures of the Python API tests: the repository's scenes and the headless runner."""
import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENES = REPO / "scenes"


@pytest.fixture(scope="session")
def runner():
    """implicit_sim_run of the workspace: $IMPLICIT_SIM_RUNNER (set by CMakeLists.txt), else the devel space's."""
    path = os.environ.get("IMPLICIT_SIM_RUNNER")
    if not path:
        for prefix in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
            candidate = pathlib.Path(prefix) / "lib" / "implicit_sim" / "implicit_sim_run"
            if candidate.is_file():
                path = str(candidate)
                break
    assert path and os.access(path, os.X_OK), \
        "implicit_sim_run not found: set IMPLICIT_SIM_RUNNER or source devel/setup.bash"
    return path


def scene(name):
    return str(SCENES / name)
