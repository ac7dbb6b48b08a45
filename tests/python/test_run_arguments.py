"""The arguments of sphxr.Run and its stepping calls, checked as the command line checks them
(app/run_arguments.h): the same bounds and the same one-line messages as sphxr.Error, thread counts
bounded by the machine, times finite and positive, a settle capped at 3600 s, file names without a NUL
byte, one "key=value" given as a str, messages escaped and bounded, a deep dict refused, Ctrl-C in a
long call, and a probe file that cannot be written failing the step that made its rows."""
import json
import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import sphxr

HIDDEN = ["\x1b", "\x07", "\n", "\r", "\x9b", "\u202e", "\u2028"]


def one_clean_line(message, longest=2000):
    assert len(message) <= longest + 40, len(message)
    for c in HIDDEN:
        assert c not in message, repr(message[:300])
    assert all(ord(c) >= 0x20 and ord(c) != 0x7F for c in message), repr(message[:300])


def refused(call, *needles):
    with pytest.raises(sphxr.Error) as e:
        call()
    message = str(e.value)
    one_clean_line(message)
    for needle in needles:
        assert needle in message, message
    return message


def cli_message(binary, *args):
    r = subprocess.run([binary, "--headless"] + [str(a) for a in args], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("sphxr: "), lines[0]
    return lines[0][len("sphxr: "):]


# ---- numbers ------------------------------------------------------------------------------------------

def test_the_module_and_the_command_line_give_the_same_bounds_and_messages(tiny_scene, sphxr_binary):
    cases = [("threads", 10 ** 9, "--threads", "1000000000"), ("threads", -1, "--threads", "-1"),
             ("settle", 4000, "--settle", "4000"), ("settle", -1, "--settle", "-1")]
    for name, value, flag, text in cases:
        message = refused(lambda: sphxr.Run(tiny_scene, **{name: value}), name)
        assert message.startswith("%s %s: must be from" % (name, text)), message
        assert cli_message(sphxr_binary, flag, text) == "--" + message, message
    # The thread count's bound is the machine's: four per core, at least 64 (--threads 1024 here passed).
    bound = max(64, 4 * os.cpu_count())
    assert sphxr._sphxr.max_threads() == bound
    refused(lambda: sphxr.Run(tiny_scene, threads=bound + 1), "threads %d: must be from 0 to %d" % (bound + 1, bound))
    assert "must be from 0 to %d" % bound in cli_message(sphxr_binary, "--threads", "1024")
    # A settle of 3600 s is the most, as --settle's.
    refused(lambda: sphxr.Run(tiny_scene, settle=3600.5), "settle 3600.5: must be from 0 to 3600 s")


def test_threads_that_are_not_a_count_are_refused_in_one_line(tiny_scene):
    refused(lambda: sphxr.Run(tiny_scene, threads=10 ** 30), "threads 1e+30: must be from 0 to")
    refused(lambda: sphxr.Run(tiny_scene, threads=10 ** 400), "threads inf: not a finite number")
    refused(lambda: sphxr.Run(tiny_scene, threads=1.5), "threads 1.5: not a whole number")
    refused(lambda: sphxr.Run(tiny_scene, threads=float("nan")), "threads nan: not a finite number")
    refused(lambda: sphxr.Run(tiny_scene, threads="2"), "threads '2': not a number")
    assert sphxr.Run(tiny_scene, threads=2.0).fluid_count == 300


def test_times_and_steps_must_be_finite_and_in_range(tiny_scene):
    run = sphxr.Run(tiny_scene, threads=1)
    begin = time.monotonic()
    refused(lambda: run.run_to(1e300), "run_to 1e+300: must be from 0 to 1e+06 s")
    refused(lambda: run.run_to(1e6 + 1), "run_to 1000001: must be from 0 to 1e+06 s")
    refused(lambda: run.run_to(math.inf), "run_to inf: not a finite number")
    refused(lambda: run.run_to(-math.inf), "run_to -inf: not a finite number")
    refused(lambda: run.run_to(math.nan), "run_to nan: not a finite number")
    refused(lambda: run.run_to(-1), "run_to -1: must be from 0 to 1e+06 s")
    refused(lambda: run.advance(math.inf), "advance inf: not a finite number")
    refused(lambda: run.advance(math.nan), "advance nan: not a finite number")
    refused(lambda: run.advance(-0.5), "advance -0.5: must be from 0 to 1e+06 s")
    refused(lambda: run.step(math.inf), "step inf: not a finite number")
    refused(lambda: run.step(math.nan), "step nan: not a finite number")
    refused(lambda: run.step(-1), "step -1: must be from 0 to")
    refused(lambda: run.step(2.5), "step 2.5: not a whole number")
    refused(lambda: run.step(10 ** 400), "step inf: not a finite number")
    for settle in (math.nan, math.inf, -0.1):
        refused(lambda: sphxr.Run(tiny_scene, settle=settle), "settle")
    assert time.monotonic() - begin < 30
    assert run.steps == 0 and run.time == 0.0  # nothing ran
    run.step(2.0).run_to(0.003).advance(0.001)
    assert run.steps >= 4 and run.time >= 0.004 - 1e-9
    refused(lambda: run.advance(1e6), "advance 1000000.0: the clock would pass 1e+06 s")


# ---- file names, overrides, messages ------------------------------------------------------------------

def test_a_nul_byte_in_a_file_name_is_refused(tmp_path, tiny_scene, tiny_scene_file):
    os.chdir(tmp_path)
    run = sphxr.Run(tiny_scene, threads=1)
    refused(lambda: run.save_state("cut\0.state"), "save_state cut\\x00.state: a file name cannot hold a NUL byte")
    refused(lambda: sphxr.Run(tiny_scene, probes_csv="p\0.csv"), "probes_csv")
    refused(lambda: sphxr.Run(tiny_scene, load_state="s\0.state"), "load_state")
    refused(lambda: sphxr.Run(str(tiny_scene_file) + "\0x"), "scene", "NUL")
    refused(lambda: sphxr.read_state("s\0.state"), "read_state")
    refused(lambda: sphxr.find_scene("stir\0"), "find_scene")
    assert sorted(os.listdir(tmp_path)) == ["tiny_probes.json"]  # no truncated "cut" or "p" was written


def test_set_as_one_str_is_one_assignment(tiny_scene):
    run = sphxr.Run(tiny_scene, set="spacing=0.02", threads=1)
    assert run.fluid_count == 25 and run.parameters()["spacing"] == pytest.approx(0.02)
    assert sphxr.scene_info("dam_break", set="stiffness=1234")["parameters"]["stiffness"] == pytest.approx(1234)
    refused(lambda: sphxr.Run(tiny_scene, set="spacing"), "--set spacing")
    refused(lambda: sphxr.Run(tiny_scene, set=5), "set: a dict, a list")
    refused(lambda: sphxr.Run(tiny_scene, set=[("spacing", 0.02)]), "set: ('spacing', 0.02): an item is")


def test_messages_are_escaped_and_bounded(tiny_scene, tmp_path):
    os.chdir(tmp_path)
    forged = "no_such\x1b]0;owned\x07\nsphxr: error: forged\u202eeman"
    message = refused(lambda: sphxr.Run(forged), "--scene no_such\\x1B]0;owned\\x07\\x0Asphxr")
    assert "\\u202E" in message
    refused(lambda: sphxr.find_scene("x\x1b[31m" + "a" * 100000), "\\x1B[31m")
    long_name = refused(lambda: sphxr.Run("b" * 100000), "--scene bbb", "... (100000 bytes): no scene of that name")
    assert len(long_name) < 400 and long_name.count("(100000 bytes)") == 1
    refused(lambda: sphxr.Run(tiny_scene, set={"spacing": "\x1b[2J" + "9" * 300000}), "--set spacing=\\x1B[2J")
    refused(lambda: sphxr.Run(tiny_scene, set={"k\u2028ey": 1}), "k\\u2028ey")
    refused(lambda: sphxr.set_log_level("\x1b[31m"), "set_log_level \\x1B[31m")
    scene = dict(tiny_scene, name="x\x1b]0;t\x07" * 1000)
    refused(lambda: sphxr.Run(scene), "name")


def test_a_deep_dict_is_refused_without_recursion(tiny_scene):
    deep = {}
    for _ in range(100000):
        deep = {"a": deep}
    refused(lambda: sphxr.Run(dict(tiny_scene, extra=deep)), "nested more than 64 levels")
    refused(lambda: sphxr.Run(dict(tiny_scene, extra=[[[[[]]]]] * 2 + [deep])), "nested more than 64 levels")
    looped = dict(tiny_scene)
    looped["self"] = looped
    refused(lambda: sphxr.Run(looped), "nested more than 64 levels")
    refused(lambda: sphxr.Run(dict(tiny_scene, extra={1, 2})), "not a JSON scene")
    assert sphxr.Run(dict(tiny_scene, comment=[[["shallow"]]])).fluid_count == 300


# ---- Ctrl-C and a full disk -------------------------------------------------------------------------

def python(code, *args):
    """`code` in a fresh interpreter, its arguments after it; output as text."""
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)] + [str(a) for a in args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize("call", ["sphxr.Run(scene, threads=1, settle=3000)",
                                  "sphxr.Run(scene, threads=1).run_to(900000)",
                                  "sphxr.Run(scene, threads=1).step(10 ** 9)"])
def test_ctrl_c_in_a_long_call_raises_keyboard_interrupt(tiny_scene, call):
    p = python("""
        import json, sys, sphxr
        scene = json.loads(sys.argv[1])
        print("ready", flush=True)
        try:
            %s
        except KeyboardInterrupt:
            print("KeyboardInterrupt", flush=True)
            sys.exit(3)
        """ % call, json.dumps(tiny_scene))
    assert p.stdout.readline() == "ready\n"
    time.sleep(1.5)  # inside the call
    assert p.poll() is None, p.communicate()
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        out, err = p.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        p.kill()
        pytest.fail("Ctrl-C did not stop %s" % call)
    assert p.returncode == 3 and "KeyboardInterrupt" in out, (p.returncode, out, err)
    assert time.monotonic() - sent < 10


def test_a_probe_file_that_cannot_be_written_fails_the_step(tiny_scene, tmp_path):
    refused(lambda: sphxr.Run(tiny_scene, probes_csv="/dev/full"), "/dev/full", "write failed")
    # A file limit of 600 bytes (RLIMIT_FSIZE, as a disk that fills): every step that returns has
    # its rows in the file, and the step whose rows do not fit raises.
    csv = tmp_path / "p.csv"
    p = python("""
        import json, resource, signal, sys, sphxr
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (600, 600))
        run = sphxr.Run(json.loads(sys.argv[1]), threads=1, probes_csv=sys.argv[2])
        for k in range(1000):
            start = run.time
            try:
                run.step(1)
            except sphxr.Error as e:
                print("error at step", run.steps, str(e))
                sys.exit(0)
            with open(sys.argv[2]) as f:
                rows = f.read().splitlines()[1:]
            # A row every 2 ms up to the step's reading (taken at its start or its end, by the method).
            least, most = int(start / 0.002 + 1e-6) + 1, int(run.time / 0.002 + 1e-6) + 1
            if not least <= len(rows) <= most:
                print("step", run.steps, "returned with", len(rows), "rows in the file, not", least, "to", most)
                sys.exit(1)
        print("never failed")
        sys.exit(1)
        """, json.dumps(tiny_scene), csv)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 0, out + err
    assert "error at step" in out and "write failed (File too large)" in out, out
