"""The sweep's table never loses a finished row (python3 -m sphxr.sweep on a Dask LocalCluster of
worker processes): it is written before the first case and replaced atomically as each case finishes;
SIGINT, SIGTERM and SIGHUP to the client write the finished rows, mark the others "not finished" and
exit 128 + the signal, as sphxr does; control characters reach neither the progress line nor the CSV."""
import csv
import os
import signal
import subprocess
import sys
import time

import pytest

A = 0.05715  # dam_break.json's column width (m)


def start(args, cwd):
    cmd = [sys.executable, "-m", "sphxr.sweep"] + [str(a) for a in args]
    return subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def finish(process, timeout=240):
    try:
        out, _ = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        out, _ = process.communicate()
        pytest.fail("the sweep did not finish in %d s:\n%s" % (timeout, out))
    return process.returncode, out


def read_table(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def wait_for_rows(path, process, ok, timeout=180):
    """Waits until the table at `path` holds `ok` finished rows; returns the table then."""
    begin = time.time()
    while time.time() - begin < timeout:
        if os.path.exists(path):
            rows = read_table(path)
            if sum(r["status"] == "ok" for r in rows) >= ok:
                return rows
        if process.poll() is not None:
            break
        time.sleep(0.05)
    pytest.fail("the table never had %d finished row(s):\n%s" % (ok, finish(process)[1]))


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_to_the_client_keeps_the_finished_rows(tmp_path, sig):
    # One worker, three cases of 1,960 particles for 1,500 steps (about 3 s each), so that the signal
    # comes with a case finished and one running.
    out_csv = tmp_path / "table.csv"
    process = start(["dam_break", "--steps", 1500, "--set", "spacing=%.9g" % (A / 14), "--grid",
                     "stiffness=31000,32000,33000", "--workers", 1, "--out", out_csv], tmp_path)
    # Before any case has finished the table is there, every case in it.
    rows = wait_for_rows(out_csv, process, 0)
    assert [r["stiffness"] for r in rows] == ["31000", "32000", "33000"]
    rows = wait_for_rows(out_csv, process, 1)
    assert rows[0]["status"] == "ok" and int(rows[0]["steps"]) == 1500, rows
    process.send_signal(sig)
    code, out = finish(process, 60)
    name = signal.Signals(sig).name
    assert code == 128 + int(sig), out
    assert "Traceback" not in out
    assert "stopped by %s: " % name in out and "written to %s" % out_csv in out, out
    rows = read_table(out_csv)
    assert len(rows) == 3
    finished = [r for r in rows if r["status"] == "ok"]
    assert rows[0]["status"] == "ok" and len(finished) >= 1
    for r in rows:
        assert r["status"] == "ok" or r["status"] == "not finished (the sweep was stopped by %s)" % name, r
    assert any(r["status"] != "ok" for r in rows), "every case had finished: the signal came too late"
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]


def test_control_characters_reach_neither_the_progress_line_nor_the_table(tmp_path, tiny_scene_file):
    out_csv = tmp_path / "table.csv"
    code, out = finish(start([tiny_scene_file, "--steps", 2, "--grid", "method=wcsph,\x1b]0;owned\x07\u202e",
                              "--workers", 2, "--out", out_csv], tmp_path))
    assert code == 1, out
    text = out_csv.read_text()
    for hidden in ("\x1b", "\x07", "\u202e"):
        assert hidden not in out and hidden not in text, (out, text)
    rows = read_table(out_csv)
    assert rows[0]["status"] == "ok"
    assert rows[1]["method"] == "\\x1B]0;owned\\x07\\u202E", rows[1]
    assert rows[1]["status"].startswith("failed: ") and "\\x1B]0;owned" in rows[1]["status"], rows[1]
    assert "case 1 method=\\x1B]0;owned\\x07\\u202E: failed: " in out, out


def test_a_table_that_cannot_be_written_as_cases_finish_goes_to_stdout(tmp_path):
    # A file limit of 400 bytes (RLIMIT_FSIZE, as a disk that fills): the first table (every case "not
    # started") fits, a table with a finished row does not. The sweep goes on, keeps its rows, and
    # prints the table on stdout at the end; the file on disk stays the last whole table.
    import resource

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (400, 400))

    out_csv = tmp_path / "table.csv"
    args = ["dam_break", "--steps", 3, "--set", "spacing=0.02", "--grid", "stiffness=31000,32000", "--workers", 1,
            "--out", out_csv]
    r = subprocess.run([sys.executable, "-m", "sphxr.sweep"] + [str(a) for a in args], cwd=tmp_path,
                       preexec_fn=limit, capture_output=True, text=True, timeout=240)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    assert r.stderr.count("cannot write the table %s (File too large): its rows are kept" % out_csv) == 1, r.stderr
    assert ("sphxr.sweep: error: --out %s: cannot write the table (File too large): it follows on stdout" % out_csv
            in r.stderr), r.stderr
    rows = list(csv.DictReader(r.stdout.splitlines()))
    assert [(row["stiffness"], row["status"], row["steps"]) for row in rows] == [("31000", "ok", "3"), ("32000", "ok", "3")]
    on_disk = read_table(out_csv)
    assert [row["status"] for row in on_disk] == ["not started", "not started"]
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]


def test_the_table_is_made_as_open_makes_a_file(tmp_path, tiny_scene_file):
    out_csv = tmp_path / "table.csv"
    old = os.umask(0o022)
    try:
        code, out = finish(start([tiny_scene_file, "--steps", 2, "--workers", 1, "--out", out_csv], tmp_path))
    finally:
        os.umask(old)
    assert code == 0, out
    assert os.stat(out_csv).st_mode & 0o777 == 0o644
