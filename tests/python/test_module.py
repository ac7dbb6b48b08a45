"""The sphxr module (docs/user/python.md): runs from a file, a name or a dict, the --set overrides,
stepping, the fields and measures as NumPy arrays, state files, the GIL released while stepping, errors
as sphxr.Error with the program's one-line message, and probes identical to `sphxr --probes`."""
import csv
import json
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import sphxr


def test_the_module_is_debians_build_and_loads_no_graphics_library():
    # python/ must not use GL or OpenXR (docs/dev/architecture.md): the extension links neither.
    out = subprocess.run(["readelf", "-d", sphxr._sphxr.__file__], capture_output=True, text=True, check=True).stdout
    needed = [line.split("[")[1].rstrip("]") for line in out.splitlines() if "(NEEDED)" in line]
    assert needed, out
    for lib in needed:
        for banned in ("libGL", "libEGL", "libOpenGL", "libglfw", "libepoxy", "libopenxr", "libX11"):
            assert not lib.startswith(banned), needed


def test_a_scene_by_name_as_the_program_finds_it():
    path = sphxr.find_scene("stir")
    assert os.path.basename(path) == "stir.json" and os.path.isfile(path)
    with pytest.raises(sphxr.Error, match=r"--scene no_such_scene: no scene of that name \(nor with \.json\) in"):
        sphxr.find_scene("no_such_scene")
    assert "spacing" in sphxr.parameter_names() and "method" in sphxr.parameter_names()


def test_a_run_from_a_dict_steps_by_steps_and_by_time(tiny_scene):
    run = sphxr.Run(tiny_scene, threads=1)
    assert run.fluid_count == 300 and run.boundary_count > 0 and run.device == "cpu"
    assert run.time == 0.0 and run.steps == 0
    run.step(5)
    assert run.steps == 5 and 0.0 < run.time <= 5 * 0.001 + 1e-9
    run.run_to(0.012)
    assert run.time >= 0.012 - 1e-9 and run.time < 0.012 + 0.001 + 1e-9
    t, n = run.time, run.steps
    run.advance(0.003)
    assert run.time >= t + 0.003 - 1e-9 and run.steps > n
    run.run_scene()  # to run.time = 0.02
    assert abs(run.time - 0.02) < 0.001 + 1e-9
    stats = run.stats()
    assert len(stats["dt"]) == run.steps and np.all(stats["dt"] > 0) and np.all(np.diff(stats["time"]) > 0)
    assert "tiny_probes" in repr(run)


def test_the_fields_are_numpy_arrays_in_particle_id_order(tiny_scene):
    run = sphxr.Run(tiny_scene, threads=1).step(20)
    p = run.particles()
    assert p["positions"].shape == (300, 3) and p["positions"].dtype == np.float32
    assert p["velocities"].shape == (300, 3) and p["velocities"].dtype == np.float32
    assert p["densities"].shape == (300,) and p["pressures"].shape == (300,)
    assert np.array_equal(p["ids"], np.arange(300))
    assert np.all(p["positions"] >= -0.01) and np.all(p["positions"][:, 0] <= 0.31)
    assert np.all(p["densities"] > 500) and np.all(p["densities"] < 1500)
    assert np.max(np.abs(p["velocities"][:, 1])) > 0  # falling
    assert np.array_equal(run.positions(), p["positions"]) and np.array_equal(run.pressures(), p["pressures"])
    s = run.summary()
    assert s["fluid"] == 300 and s["steps"] == 20 and s["time"] == pytest.approx(run.time)
    assert 0 <= s["mean_density_error"] < 0.1 and s["wall_seconds"] > 0


def test_overrides_as_set_does(tiny_scene):
    run = sphxr.Run(tiny_scene, set={"spacing": 0.02, "method": "dfsph", "density_tolerance": 0.5}, threads=1)
    params = run.parameters()
    assert params["method"] == "dfsph" and params["spacing"] == pytest.approx(0.02)
    assert params["density_tolerance"] == pytest.approx(0.5)
    assert run.fluid_count == 5 * 5 * 1  # the block in whole layers of 2 cm
    same = sphxr.Run(tiny_scene, set=["spacing=0.02", "method=dfsph", "density_tolerance=0.5"], threads=1)
    assert same.parameters() == params
    info = sphxr.scene_info(sphxr.find_scene("dam_break"), set={"stiffness": 1234.0})
    assert info["parameters"]["stiffness"] == pytest.approx(1234.0) and info["dam_break_column_width"] > 0


def test_errors_are_sphxr_errors_with_the_one_line_message(tiny_scene, tmp_path):
    with pytest.raises(sphxr.Error) as e:
        sphxr.Run(tiny_scene, set={"no_such_parameter": 1})
    assert "no_such_parameter" in str(e.value) and "\n" not in str(e.value)
    assert isinstance(e.value, RuntimeError)
    bad = dict(tiny_scene, solver=dict(tiny_scene["solver"], spacing=-1.0))
    with pytest.raises(sphxr.Error, match="spacing") as e:
        sphxr.Run(bad)
    assert "\n" not in str(e.value)
    with pytest.raises(sphxr.Error, match="device"):
        sphxr.Run(tiny_scene, device="abacus")
    with pytest.raises(sphxr.Error):
        sphxr.Run(str(tmp_path / "missing.json"))
    with pytest.raises(sphxr.Error, match="probes"):
        sphxr.Run("dam_break", set={"spacing": 0.02}).probes()
    with pytest.raises(sphxr.Error):
        sphxr.read_state(str(tmp_path / "missing.state"))


def test_a_state_file_saved_and_loaded(tiny_scene, tmp_path):
    state = tmp_path / "tiny.state"
    first = sphxr.Run(tiny_scene, threads=1).step(10)
    first.save_state(state)
    saved = sphxr.read_state(state)
    assert saved["scene"] == "tiny_probes" and saved["step"] == 10 and saved["fluid"] == 300
    assert saved["time"] == pytest.approx(first.time)
    order = np.argsort(saved["ids"])
    assert np.array_equal(saved["positions"][order], first.positions())

    second = sphxr.Run(tiny_scene, threads=1, load_state=state)
    assert second.steps == 10 and second.time == pytest.approx(first.time)
    assert np.array_equal(second.positions(), first.positions())
    assert np.array_equal(second.velocities(), first.velocities())
    first.step(10)
    second.step(10)
    assert second.steps == 20
    # The state file holds the whole state: the continued run is the uninterrupted one, bit for bit.
    assert np.array_equal(second.positions(), first.positions())
    with pytest.raises(sphxr.Error, match="settle"):
        sphxr.Run(tiny_scene, load_state=state, settle=1.0)


def test_the_gil_is_released_while_it_steps(tiny_scene):
    run = sphxr.Run(tiny_scene, set={"spacing": 0.005}, threads=1)  # 2,400 particles: a slow step
    span = {}

    def work():
        span["begin"] = time.perf_counter()
        run.step(150)
        span["end"] = time.perf_counter()

    thread = threading.Thread(target=work)
    ticks = []
    thread.start()
    while thread.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    thread.join()
    begin, end = span["begin"], span["end"]
    assert end - begin > 0.05, "the run was too short to tell"
    # Python ran in the main thread during the middle half of the call: the call did not hold the GIL.
    inside = [t for t in ticks if begin + 0.25 * (end - begin) < t < begin + 0.75 * (end - begin)]
    assert len(inside) >= 3, (end - begin, len(ticks))


def test_probes_match_the_programs_probes_csv(tiny_scene_file, tmp_path, sphxr_binary):
    cli_csv = tmp_path / "cli_probes.csv"
    subprocess.run([sphxr_binary, "--headless", "--scene", str(tiny_scene_file), "--threads", "1", "--probes",
                    str(cli_csv)], check=True, capture_output=True, cwd=tmp_path, timeout=120)
    py_csv = tmp_path / "py_probes.csv"
    run = sphxr.Run(tiny_scene_file, threads=1, probes_csv=py_csv).run_scene()
    table = run.probes()
    with open(cli_csv) as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert list(table) == header == ["time", "step", "P1_p", "P2_p", "G1_level"]
    assert len(body) == len(table["time"]) >= 10
    for k, column in enumerate(header):
        expected = np.array([float(r[k]) if r[k] else np.nan for r in body])
        np.testing.assert_array_equal(table[column], expected, err_msg=column)
    assert np.all(np.isfinite(table["P1_p"])) and np.nanmax(table["P1_p"]) > 100  # under the column: wet
    # The module writes the file --probes writes, byte for byte.
    del run
    assert py_csv.read_bytes() == cli_csv.read_bytes()


def test_a_dam_break_measures_its_front(tmp_path):
    run = sphxr.Run("dam_break", set={"spacing": 0.05715 / 8}, threads=1).run_to(0.04)
    d = run.dam_break()
    assert len(d["T"]) == run.steps + 1 and d["Z"][0] == pytest.approx(1.0, abs=0.2)
    assert d["Z"][-1] > d["Z"][0] and d["H"][-1] < d["H"][0]
    assert run.summary()["surge_front"] == pytest.approx(d["Z"][-1])
    assert sphxr.Run("stir", set={"spacing": 0.04}).dam_break() is None


def test_the_example_script_runs(tmp_path):
    example = os.environ.get("SPHXR_PYTHON_EXAMPLE")
    if not example:
        pytest.skip("SPHXR_PYTHON_EXAMPLE is not set (ctest sets it)")
    out = subprocess.run([sys.executable, example, "--quick"], capture_output=True, text=True, cwd=tmp_path,
                         timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "front" in out.stdout
