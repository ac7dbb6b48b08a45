"""python3 -m sphxr.sweep: runs a scene over a grid of overrides on Dask distributed (docs/user/python.md).

    python3 -m sphxr.sweep dam_break --time 0.05 --grid spacing=0.004,0.003 --grid method=wcsph,dfsph

Each case (one point of the grid) is one task: a LocalCluster of worker processes on this machine by
default, or the workers of any Dask scheduler (--scheduler tcp://host:8786). The table (--out, CSV) has
one row per case, in grid order: its parameters, its status, attempts, wall time, steps, density
errors, the Martin & Moyce front deviation for a dam-break scene and probe errors for --compare. A case
whose worker dies is run again on another worker (Dask reschedules it, up to --allowed-failures
deaths); past that, or when the run itself fails, its row says so: no case is ever missing.

The table is written before the first case (an --out that cannot be written is refused at once) and
again, atomically, as each case finishes; SIGINT, SIGTERM and SIGHUP stop the sweep with the finished
rows written and the others "not finished", and it exits 128 + the signal's number, as sphxr does.
Arguments are checked as sphxr checks its own (the same bounds and messages), and an expected failure
is one line, never a traceback.
"""
import argparse
import csv
import itertools
import json
import math
import os
import signal
import socket
import sys
import tempfile
import time

import numpy as np

EPILOG = """grid axes:
  --grid KEY=V1,V2,...          one parameter, several values (the --set names: spacing, method,
                                stiffness, density_tolerance, reuse.threshold, ...)
  --grid K1,K2=A1:B1,A2:B2,...  several parameters that change together (a method and its knob)
  The cases are the product of the axes; --set KEY=VALUE fixes a parameter for every case.

bench's trade table (docs/dev/tradeoff.md) as a sweep:
  python3 -m sphxr.sweep dam_break --time 0.19 \\
    --grid spacing=0.00408214286,0.0028575,0.00219807692 \\
    --grid method,stiffness,density_tolerance=wcsph:16000:0.1,wcsph:32000:0.1,wcsph:128000:0.1,dfsph:32000:1,dfsph:32000:0.1,dfsph:32000:0.01 \\
    --out tradeoff_sweep.csv
"""


# ---- the grid --------------------------------------------------------------------------------------
def parse_axis(text):
    """'spacing=0.02,0.015' -> [{'spacing': '0.02'}, {'spacing': '0.015'}]; 'a,b=1:2,3:4' -> zipped."""
    if "=" not in text:
        raise ValueError("--grid %s: expected KEY=V1,V2,... (or K1,K2=A1:B1,A2:B2)" % text)
    keys, values = text.split("=", 1)
    keys = [k.strip() for k in keys.split(",") if k.strip()]
    points = []
    for value in values.split(","):
        parts = value.split(":") if len(keys) > 1 else [value]
        if len(parts) != len(keys) or any(p.strip() == "" for p in parts):
            raise ValueError("--grid %s: '%s' needs %d value(s) for %s" % (text, value, len(keys), ",".join(keys)))
        points.append(dict(zip(keys, (p.strip() for p in parts))))
    return keys, points


def make_cases(axes):
    keys = [k for ks, _ in axes for k in ks]
    if len(set(keys)) != len(keys):
        raise ValueError("--grid: a parameter is on two axes (%s)" % ", ".join(keys))
    cases = []
    for combo in itertools.product(*[points for _, points in axes]):
        case = {}
        for point in combo:
            case.update(point)
        cases.append(case)
    return keys, cases


# ---- measures (on the worker) ---------------------------------------------------------------------
def read_series(path, column=None, tscale=1.0, vscale=1.0):
    """(t, v) arrays from a measured CSV: '#' comments, a header; `column` the value column (default the
    second), or the Martin & Moyce file's 'front' series when it has a 'series' column."""
    times, values = [], []
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if line.strip() and not line.startswith("#"))]
    header, body = rows[0], rows[1:]
    if header[0] == "series":  # tests/data/martin_moyce_1952.csv
        body = [[r[1], r[2]] for r in body if r[0] == (column or "front")]
        k = 1
    else:
        k = header.index(column) if column in header else 1
    for r in body:
        times.append(float(r[0]) * tscale)
        values.append(float(r[k]) * vscale)
    return np.array(times), np.array(values)


def martin_moyce(run, measured, window):
    """Martin & Moyce (1952) as the validation test and bench/tradeoff.cpp judge it (sim::JudgeMartinMoyce,
    docs/dev/physics.md): one gate lag t0 for the front and the column height, scanned in steps of 0.05 ms
    over [0, the first measured front time], minimising the summed squared relative deviations of the
    points the run reached (fronts with window[0] <= T <= window[1], heights with tau <= 3); then the RMS,
    largest and mean of Z_sim(t - t0) / Z_measured - 1, and the largest column-height deviation."""
    d = run.dam_break()
    if d is None or measured is None:
        return {}
    (tf, zf), (th, hh) = measured["front"], measured["height"]
    to_t = d["T"][-1] / d["time"][-1] if d["time"][-1] > 0 else 1.0  # sqrt(2 g / a)
    to_tau = to_t / math.sqrt(2.0)
    t_end = d["time"][-1]
    kf = (tf >= window[0]) & (tf <= window[1]) & (tf / to_t <= t_end)
    kh = (th <= 3.0) & (th / to_tau <= t_end)
    out = {"final_Z": float(d["Z"][-1]), "final_H": float(d["H"][-1]), "mm_points": int(kf.sum()),
           "mm_front_rms": math.nan, "mm_front_max": math.nan, "mm_front_bias": math.nan,
           "mm_gate_lag_ms": math.nan, "mm_height_max": math.nan}
    if not kf.any():
        return out

    def deviations(lag):
        rf = np.interp(tf[kf] / to_t - lag, d["time"], d["Z"]) / zf[kf] - 1.0
        rh = np.interp(th[kh] / to_tau - lag, d["time"], d["H"]) / hh[kh] - 1.0
        return rf, rh

    limit = tf[0] / to_t
    steps = int(math.ceil(limit / 5e-5))
    lags = [limit * k / steps for k in range(steps + 1)]
    lag = min(lags, key=lambda L: sum(float(np.sum(x ** 2)) for x in deviations(L)))
    rf, rh = deviations(lag)
    out.update(mm_front_rms=float(np.sqrt(np.mean(rf ** 2))), mm_front_max=float(np.max(np.abs(rf))),
               mm_front_bias=float(np.mean(rf)), mm_gate_lag_ms=1e3 * lag,
               mm_height_max=float(np.max(np.abs(rh))) if len(rh) else math.nan)
    return out


def probe_errors(run, compares):
    """For each --compare COLUMN=FILE: the probe column interpolated at the measured times the run
    covers (dry rows left out); RMS of the difference, and that RMS over the largest |measured|."""
    if not compares:
        return {}
    table = run.probes()
    out = {}
    for column, (t_meas, v_meas) in compares.items():
        if column not in table:
            raise KeyError("--compare %s: the scene has no such probe column (%s)"
                           % (column, ", ".join(c for c in table if c not in ("time", "step"))))
        t, v = table["time"], table[column]
        wet = ~np.isnan(v)
        keep = (t_meas >= t[0]) & (t_meas <= t[-1]) if len(t) else np.zeros(len(t_meas), bool)
        out[column + "_points"] = int(keep.sum())
        out[column + "_rms"] = out[column + "_rms_rel"] = math.nan
        if keep.any() and wet.any():
            diff = np.interp(t_meas[keep], t[wet], v[wet]) - v_meas[keep]
            rms = float(np.sqrt(np.mean(diff ** 2)))
            out[column + "_rms"] = rms
            out[column + "_rms_rel"] = rms / max(float(np.max(np.abs(v_meas))), 1e-30)
    return out


def run_case(spec):
    """One case, on a worker: a dict in, the row's measures out. A run that fails (sphxr.Error) is a row
    with status 'failed: MESSAGE'; the worker dying is Dask's to see (the case is rescheduled)."""
    import sphxr
    sphxr.set_log_level(spec.get("log", "warn"))
    case_dir = spec["case_dir"]
    os.makedirs(case_dir, exist_ok=True)
    # One line per attempt, written before the run: the row's attempts, and the process to look at.
    with open(os.path.join(case_dir, "attempts"), "a") as f:
        f.write("%d %s %.3f\n" % (os.getpid(), socket.gethostname(), time.time()))
    with open(os.path.join(case_dir, "attempts")) as f:
        attempts = sum(1 for _ in f)
    row = {"status": "ok", "attempts": attempts, "host": socket.gethostname(), "pid": os.getpid()}
    begin = time.perf_counter()
    # The scene's file where this worker sees it (this machine, a shared file system), else the text the
    # client read (a worker on another machine; paths inside the scene are then the client's).
    scene = spec["scene"] if os.path.isfile(spec["scene"]) else json.loads(spec["scene_text"])
    try:
        run = sphxr.Run(scene, set=spec["sets"], device=spec["device"], threads=spec["threads"],
                        settle=spec["settle"], base_dir=spec["base_dir"],
                        probes_csv=os.path.join(case_dir, "probes.csv") if spec["has_probes"] else None)
        if spec["steps"]:
            run.step(spec["steps"])
        elif spec["time"]:
            run.run_to(spec["time"])
        else:
            run.run_scene()
        s = run.summary()
        row.update(wall_s=time.perf_counter() - begin, step_wall_s=float(s["step_seconds"]), steps=int(s["steps"]),
                   sim_time_s=float(s["time"]), fluid=int(s["fluid"]), spacing_m=float(s["spacing"]),
                   method=run.parameters()["method"],
                   mean_density_error=float(s["mean_density_error"]),
                   time_mean_density_error=float(s["time_mean_density_error"]),
                   peak_mean_density_error=float(s["peak_mean_density_error"]),
                   max_density_error=float(s["max_density_error"]), max_speed=float(s["max_speed"]),
                   density_iterations=float(s.get("density_iterations", 0.0)),
                   clamped_events=int(s["clamped_events"]), dt_clamped_steps=int(s["dt_clamped_steps"]))
        row.update(martin_moyce(run, spec["measured"], spec["mm_window"]))
        row.update(probe_errors(run, spec["compares"]))
    except (sphxr.Error, KeyError, ValueError) as e:
        row.update(status="failed: %s" % sphxr.show_text(str(e), 1000), wall_s=time.perf_counter() - begin)
    return row


# ---- the client -------------------------------------------------------------------------------------
class SweepError(Exception):
    """An expected failure of the client (a bad argument, an unwritable table, no scheduler): one line."""


class Stopped(Exception):
    """SIGTERM or SIGHUP to the client (SIGINT is Python's KeyboardInterrupt)."""

    def __init__(self, signum):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m sphxr.sweep", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="a scene file or a scene's name (as sphxr --scene)")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2", help="an axis of the grid")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="an override for every case")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--time", default=None, help="simulated s per case (default: the scene's run)")
    length.add_argument("--steps", default=None, help="steps per case instead of a time")
    p.add_argument("--settle", default=None, help="s of settling first (default: the scene's run.settle)")
    p.add_argument("--out", default="sweep.csv", help="the table (CSV, one row per case; default sweep.csv)")
    p.add_argument("--work-dir", default=None, help="each case's folder: attempts, probes.csv (default: OUT_cases; "
                   "on a cluster of machines, a folder every worker sees)")
    p.add_argument("--scheduler", default=None, metavar="ADDR", help="a Dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", default=None, help="LocalCluster worker processes (default: cores / threads)")
    p.add_argument("--threads", default="1", help="solver threads per case (default 1)")
    p.add_argument("--device", default="cpu", help="auto, cpu, cuda or cpu-reference (default cpu)")
    p.add_argument("--allowed-failures", type=int, default=2,
                   help="worker deaths a case survives before it is reported failed (default 2; with "
                        "--scheduler, the scheduler's own distributed.scheduler.allowed-failures counts)")
    p.add_argument("--measured", default=None, help="Martin & Moyce data (default: sphxr.data_dir()'s)")
    p.add_argument("--mm-window", default="1.0,3.3", help="T range of the front comparison (default 1.0,3.3)")
    p.add_argument("--compare", action="append", default=[], metavar="COLUMN=FILE[:TSCALE[:VSCALE]]",
                   help="a probe column against a measured CSV (time, value; each scaled)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    return p.parse_args(argv)


def check_numbers(args):
    """The run arguments through sphxr's own check (app/run_arguments.h): --time inf, --steps -5,
    --workers -1 are refused as `sphxr --time inf` is, in the same words."""
    import sphxr

    for flag in ("time", "steps", "settle", "threads", "workers"):
        text = getattr(args, flag)
        if text is not None:
            value = sphxr._sphxr.parse_argument("--" + flag, text)
            setattr(args, flag, int(value) if flag in ("steps", "threads", "workers") else value)
    if not 0 <= args.allowed_failures <= 100:
        raise SweepError("--allowed-failures %d: must be from 0 to 100" % args.allowed_failures)
    args.mm_window = parse_window(args.mm_window)


def parse_window(text):
    """'1.0,3.3' -> [1.0, 3.3]: two finite numbers, the first below the second."""
    import sphxr

    parts = text.split(",")
    try:
        window = [float(x) for x in parts]
    except ValueError:
        window = []
    if len(window) != 2 or not all(math.isfinite(x) for x in window) or not 0 <= window[0] < window[1]:
        raise SweepError("--mm-window %s: expected LO,HI, two numbers from 0 with LO < HI (default 1.0,3.3)"
                         % sphxr.show_text(text))
    return window


def check_scheduler(address, timeout=5.0):
    """A scheduler's address answers a TCP connection within `timeout` s (Client would wait 30 s and
    end in a traceback)."""
    import sphxr

    shown = sphxr.show_text(address)
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme not in ("tcp", "tls"):
        return  # inproc:// or ucx://: Client says
    host, _, port = rest.rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise SweepError("--scheduler %s: expected tcp://HOST:PORT" % shown)
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as e:
        raise SweepError("--scheduler %s: cannot reach it (%s)" % (shown, e.strerror or e.__class__.__name__)) from None


def load_compares(items):
    out = {}
    for item in items:
        column, _, rest = item.partition("=")
        parts = rest.split(":")
        if not column or not parts[0]:
            raise ValueError("--compare %s: expected COLUMN=FILE[:TSCALE[:VSCALE]]" % item)
        scales = [float(x) for x in parts[1:3]] + [1.0] * (2 - len(parts[1:3]))
        # The measured file's value column: the probe's name (P1 for P1_p), else its second column.
        out[column] = read_series(parts[0], column.rsplit("_", 1)[0], scales[0], scales[1])
    return out


def shown(text, max_bytes=300):
    """Text for the progress line and the table: control, bidi and other hidden characters escaped."""
    import sphxr

    return sphxr.show_text(str(text), max_bytes)


def label(case):
    return " ".join("%s=%s" % (shown(k, 60), shown(v, 60)) for k, v in case.items()) or "(the scene)"


def check_out(path):
    """--out can take the table: a regular file or none yet, in a folder that exists."""
    if os.path.lexists(path) and not os.path.isfile(path):
        raise SweepError("--out %s: not a regular file (a folder or a device); give a file name" % shown(path))
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SweepError("--out %s: the folder %s does not exist; make it first" % (shown(path), shown(folder)))


def format_table(f, keys, cases, rows):
    """The table as CSV into the open file `f`: a row per case, its parameters and measures."""
    columns = ["case"] + [shown(k) for k in keys] + ["status", "attempts"]
    for r in rows:
        for c in r:
            if c not in columns:
                columns.append(c)
    w = csv.DictWriter(f, fieldnames=columns, restval="")
    w.writeheader()
    for k, (case, r) in enumerate(zip(cases, rows)):
        row = {c: shown(v, 1000) if isinstance(v, str) else v for c, v in r.items()}
        w.writerow(dict(row, case=k, **{shown(c): shown(v) for c, v in case.items()}))


def write_table(path, keys, cases, rows):
    """The table, replaced atomically (a temporary file beside it, then os.replace): a reader or a kill
    sees the old table or the new one, never half of one."""
    folder, name = os.path.split(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix="." + name + ".", suffix=".tmp", dir=folder)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # as open() would make it (mkstemp's is 0600)
        with os.fdopen(fd, "w", newline="") as f:
            format_table(f, keys, cases, rows)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    import sphxr
    try:
        return run_sweep(args)
    except (SweepError, sphxr.Error) as e:
        print("sphxr.sweep: error: %s" % shown(str(e), 2000), file=sys.stderr)
        return 2


def run_sweep(args):
    import sphxr
    try:
        check_numbers(args)
        axes = [parse_axis(g) for g in args.grid]
        keys, cases = make_cases(axes)
        compares = load_compares(args.compare)
        window = args.mm_window
        scene_path = sphxr.find_scene(args.scene)
        info = sphxr.scene_info(scene_path, set=args.set)
        measured = None
        if info["dam_break_column_width"] is not None:
            mm_file = args.measured or os.path.join(sphxr.data_dir(), "martin_moyce_1952.csv")
            measured = {"front": read_series(mm_file, "front"), "height": read_series(mm_file, "height")}
        check_out(args.out)
        with open(scene_path) as f:
            scene_text = f.read()
        if args.scheduler:
            check_scheduler(args.scheduler)
    except (ValueError, OSError) as e:
        raise SweepError(str(e)) from None
    has_probes = info["probe_columns"] is not None
    rows = [{"status": "not started", "attempts": 0} for _ in cases]
    try:
        write_table(args.out, keys, cases, rows)  # before any case: the table can be written
    except OSError as e:
        raise SweepError("--out %s: cannot write the table (%s)" % (shown(args.out), e.strerror or e)) from None
    work_dir = os.path.abspath(args.work_dir or os.path.splitext(args.out)[0] + "_cases")
    try:
        os.makedirs(work_dir, exist_ok=True)
    except OSError as e:
        raise SweepError("--work-dir %s: cannot make it (%s)" % (shown(work_dir), e.strerror or e)) from None
    specs = []
    for k, case in enumerate(cases):
        specs.append({"scene": os.path.abspath(scene_path), "scene_text": scene_text, "base_dir": os.path.dirname(os.path.abspath(scene_path)),
                      "sets": list(args.set) + ["%s=%s" % kv for kv in case.items()], "device": args.device,
                      "threads": args.threads, "settle": args.settle, "steps": args.steps, "time": args.time,
                      "case_dir": os.path.join(work_dir, "case_%03d" % k), "has_probes": has_probes,
                      "measured": measured, "mm_window": window, "compares": compares})
        # A case's folder starts empty: its attempts are this sweep's.
        try:
            os.remove(os.path.join(specs[-1]["case_dir"], "attempts"))
        except FileNotFoundError:
            pass

    say = (lambda *a: None) if args.quiet else (lambda msg: print("sphxr.sweep: " + msg, file=sys.stderr, flush=True))
    stopped_by = None
    unwritten = None  # why the table could not be written as the last case finished (a full disk)
    done = failed = 0

    def save():
        """Writes the table; a failure (a full disk) is said once, and the sweep goes on: the rows are
        kept, and written when the table next can be, or printed at the end."""
        nonlocal unwritten
        try:
            write_table(args.out, keys, cases, rows)
            if unwritten is not None:
                say("the table %s is written again" % shown(args.out))
            unwritten = None
        except OSError as e:
            if unwritten is None:
                say("cannot write the table %s (%s): its rows are kept" % (shown(args.out), e.strerror or e))
            unwritten = e.strerror or str(e)

    cluster = client = None

    def stop(signum, frame):
        raise Stopped(signum)

    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGHUP)}
    try:
        import dask
        from distributed import Client, LocalCluster, as_completed
        dask.config.set({"distributed.scheduler.allowed-failures": args.allowed_failures})
        if args.scheduler:
            try:
                client = Client(args.scheduler, timeout=10)
            except (OSError, TimeoutError) as e:
                raise SweepError("--scheduler %s: cannot connect (%s)" % (shown(args.scheduler), shown(e))) from None
        else:
            workers = args.workers or max(1, (os.cpu_count() or 1) // max(1, args.threads))
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
        say("%d case(s) of %s on %s" % (len(cases), shown(scene_path), shown(client.scheduler.address) if args.scheduler else
                                        "a local cluster of %d worker processes" % len(cluster.workers)))
        futures = {}
        for k, spec in enumerate(specs):
            futures[client.submit(run_case, spec, key="sphxr-case-%03d-%s" % (k, os.urandom(4).hex()), pure=False)] = k
        for k in range(len(rows)):
            rows[k] = {"status": "not finished", "attempts": 0}
        begin = time.time()
        for future in as_completed(futures):
            k = futures[future]
            try:
                rows[k] = future.result()
            except Exception as e:  # KilledWorker (the worker died allowed-failures + 1 times), or a crash
                attempts = 0
                try:
                    with open(os.path.join(specs[k]["case_dir"], "attempts")) as f:
                        attempts = sum(1 for _ in f)
                except OSError:
                    pass
                rows[k] = {"status": "failed: %s: %s" % (type(e).__name__, shown(e, 300)), "attempts": attempts}
            done += 1
            ok = rows[k]["status"] == "ok"
            failed += 0 if ok else 1
            save()
            say("[%d/%d, %d failed, %.0f s] case %d %s: %s%s%s" % (
                done, len(cases), failed, time.time() - begin, k, label(cases[k]), shown(rows[k]["status"]),
                " in %.1f s" % rows[k]["wall_s"] if ok else "",
                " (attempt %d)" % rows[k]["attempts"] if rows[k].get("attempts", 1) > 1 else ""))
    except KeyboardInterrupt:
        stopped_by = signal.SIGINT
    except Stopped as e:
        stopped_by = e.signum
    finally:
        # Further signals wait: the table is written once more, then the cluster closes.
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(sig, signal.SIG_IGN)
        if stopped_by is not None:
            name = signal.Signals(stopped_by).name
            for k in range(len(rows)):
                if rows[k]["status"] in ("not started", "not finished"):
                    rows[k] = {"status": "not finished (the sweep was stopped by %s)" % name, "attempts": 0}
            save()
            say("stopped by %s: %d of %d case(s) finished%s" % (
                name, done, len(cases), ", written to %s" % shown(args.out) if unwritten is None else ""))
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if unwritten is not None:
        # The rows that could not reach --out are not lost: the table goes to stdout.
        print("sphxr.sweep: error: --out %s: cannot write the table (%s): it follows on stdout"
              % (shown(args.out), unwritten), file=sys.stderr, flush=True)
        format_table(sys.stdout, keys, cases, rows)
        sys.stdout.flush()
    if stopped_by is not None:
        return 128 + int(stopped_by)
    if unwritten is not None:
        return 2
    say("wrote %d row(s) to %s (%d failed)" % (len(rows), shown(args.out), failed))
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    # The tasks are this module's functions by name (sphxr.sweep.run_case), not __main__'s: a worker
    # imports the installed module instead of receiving a pickled copy of this file's code.
    from sphxr import sweep

    sys.exit(sweep.main())
