"""Shared fixtures of the Python suite (tests/CMakeLists.txt runs it from ctest with Debian's python3).

ctest sets PYTHONPATH to the build's package (<build>/python) and SPHXR_BINARY to the sphxr program;
the sweeps' workers inherit both.
"""
import json
import os

import pytest

# A small dam break with probes: 10 x 10 x 3 = 300 particles at 1 cm against the x- wall of a 0.3 m tank,
# a pressure sensor under the column (always wet), one on the far wall (dry until the surge arrives) and
# a gauge in the column.
TINY_PROBES_SCENE = {
    "name": "tiny_probes",
    "solver": {"spacing": 0.01, "stiffness": 20000.0, "viscosity": 0.02, "max_dt": 0.001},
    "tank": {"min": [0.0, 0.0, 0.0], "max": [0.3, 0.2, 0.03]},
    "fluid": [{"min": [0.0, 0.0, 0.0], "max": [0.1, 0.1, 0.03]}],
    "probes": {
        "every": 0.002,
        "pressure": [{"name": "P1", "at": [0.0, 0.02, 0.015], "normal": [-1, 0, 0]},
                     {"name": "P2", "at": [0.3, 0.02, 0.015], "normal": [1, 0, 0]}],
        "level": [{"name": "G1", "x": 0.05, "z": 0.015}],
    },
    "run": {"time": 0.02},
}


@pytest.fixture
def tiny_scene():
    """A copy of TINY_PROBES_SCENE (a dict: the test may change it)."""
    return json.loads(json.dumps(TINY_PROBES_SCENE))


@pytest.fixture
def tiny_scene_file(tmp_path, tiny_scene):
    path = tmp_path / "tiny_probes.json"
    path.write_text(json.dumps(tiny_scene, indent=2))
    return path


@pytest.fixture
def sphxr_binary():
    binary = os.environ.get("SPHXR_BINARY", "")
    if not binary or not os.access(binary, os.X_OK):
        pytest.skip("SPHXR_BINARY is not set to the sphxr program (ctest sets it)")
    return binary


@pytest.fixture(autouse=True)
def quiet_log():
    import sphxr

    sphxr.set_log_level("warn")
    yield
