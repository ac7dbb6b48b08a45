"""python3 -m sphxr.sweep refuses what sphxr refuses, before any cluster starts and before any case:
the run arguments through the program's own check (the same bounds and words), --workers from 1 to
the machine's bound, --mm-window as two numbers, a scheduler that does not answer, and an --out that
cannot take the table. Each is one line and exit 2, with no traceback and no table."""
import os
import subprocess
import sys
import time

import pytest

import sphxr


def sweep(args, cwd, timeout=60):
    begin = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "sphxr.sweep"] + [str(a) for a in args], cwd=cwd, capture_output=True,
                       text=True, timeout=timeout)
    return r.returncode, r.stdout + r.stderr, time.monotonic() - begin


def refused(tmp_path, args, message, within=20):
    out_csv = tmp_path / "table.csv"
    code, out, seconds = sweep(["dam_break"] + args + ["--out", out_csv], tmp_path)
    assert code == 2, out
    lines = out.strip().splitlines()
    assert len(lines) == 1 and lines[0] == "sphxr.sweep: error: " + message, out
    assert "Traceback" not in out
    assert not out_csv.exists() and not (tmp_path / "table_cases").exists()
    assert seconds < within, seconds


@pytest.mark.parametrize("args,message", [
    (["--time", "inf"], "--time inf: not a finite number"),
    (["--time", "1e300"], "--time 1e300: must be from 1e-09 to 1e+06 s"),
    (["--time", "nan"], "--time nan: not a finite number"),
    (["--time", "-1"], "--time -1: must be from 1e-09 to 1e+06 s"),
    (["--steps", "-5"], "--steps -5: must be from 1 to 1099511627776"),
    (["--steps", "1.5"], "--steps 1.5: not an integer"),
    (["--settle", "4000"], "--settle 4000: must be from 0 to 3600 s"),
    (["--threads", "1000000000"], "--threads 1000000000: must be from 0 to %d (0: all cores; four per core here, "
                                  "at least 64)" % max(64, 4 * os.cpu_count())),
    (["--workers", "-1"], "--workers -1: must be from 1 to %d (four per core here, at least 64)" % max(64, 4 * os.cpu_count())),
    (["--workers", "0"], "--workers 0: must be from 1 to %d (four per core here, at least 64)" % max(64, 4 * os.cpu_count())),
    (["--workers", "1000000000"], "--workers 1000000000: must be from 1 to %d (four per core here, at least 64)"
                                  % max(64, 4 * os.cpu_count())),
    (["--mm-window", "1"], "--mm-window 1: expected LO,HI, two numbers from 0 with LO < HI (default 1.0,3.3)"),
    (["--mm-window", "3,1"], "--mm-window 3,1: expected LO,HI, two numbers from 0 with LO < HI (default 1.0,3.3)"),
    (["--mm-window", "nan,2"], "--mm-window nan,2: expected LO,HI, two numbers from 0 with LO < HI (default 1.0,3.3)"),
    (["--allowed-failures", "-1"], "--allowed-failures -1: must be from 0 to 100"),
])
def test_run_arguments_are_refused_as_sphxr_refuses_them(tmp_path, args, message):
    refused(tmp_path, args, message)


def test_the_words_are_sphxrs_own(tmp_path, sphxr_binary):
    r = subprocess.run([sphxr_binary, "--headless", "--time", "inf"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.strip() == "sphxr: --time inf: not a finite number", r.stderr
    refused(tmp_path, ["--time", "inf"], "--time inf: not a finite number")


def test_an_unreachable_scheduler_is_refused_at_once(tmp_path):
    import socket

    with socket.socket() as s:  # a port nobody listens on: bound, never listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        refused(tmp_path, ["--scheduler", "tcp://127.0.0.1:%d" % port],
                "--scheduler tcp://127.0.0.1:%d: cannot reach it (Connection refused)" % port, within=15)
    refused(tmp_path, ["--scheduler", "tcp://nohost"], "--scheduler tcp://nohost: expected tcp://HOST:PORT")


def test_an_out_that_cannot_take_the_table_is_refused_before_any_case(tmp_path):
    folder = tmp_path / "a_folder"
    folder.mkdir()
    code, out, _ = sweep(["dam_break", "--time", "0.01", "--out", folder], tmp_path)
    assert code == 2 and out.strip() == "sphxr.sweep: error: --out %s: not a regular file (a folder or a device); " \
                                        "give a file name" % folder, out
    code, out, _ = sweep(["dam_break", "--time", "0.01", "--out", "/dev/full"], tmp_path)
    assert code == 2 and "--out /dev/full: not a regular file" in out and len(out.strip().splitlines()) == 1, out
    missing = tmp_path / "no_such_folder" / "t.csv"
    code, out, _ = sweep(["dam_break", "--time", "0.01", "--out", missing], tmp_path)
    assert code == 2 and out.strip() == "sphxr.sweep: error: --out %s: the folder %s does not exist; make it first" % (
        missing, missing.parent), out
    assert sorted(os.listdir(tmp_path)) == ["a_folder"] and os.listdir(folder) == []
    assert "Traceback" not in out
