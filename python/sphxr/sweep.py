"""python3 -m sphxr.sweep: runs a scene over a grid of overrides on Dask distributed (docs/user/python.md).

    python3 -m sphxr.sweep dam_break --time 0.05 --grid spacing=0.004,0.003 --grid method=wcsph,dfsph

Each case (one point of the grid) is one task: a LocalCluster of worker processes on this machine by
default, or the workers of any Dask scheduler (--scheduler tcp://host:8786). The table (--out, CSV) has
one row per case, in grid order: its parameters, its status, attempts, wall time, steps, density
errors, the Martin & Moyce front deviation for a dam-break scene and probe errors for --compare. A case
whose worker dies is run again on another worker (Dask reschedules it, up to --allowed-failures
deaths); past that, or when the run itself fails, its row says so: no case is ever missing.
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
        if spec["steps"] > 0:
            run.step(spec["steps"])
        elif spec["time"] > 0:
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
        row.update(status="failed: %s" % str(e).replace("\n", " "), wall_s=time.perf_counter() - begin)
    return row


# ---- the client -------------------------------------------------------------------------------------
def parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m sphxr.sweep", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="a scene file or a scene's name (as sphxr --scene)")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2", help="an axis of the grid")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="an override for every case")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--time", type=float, default=0.0, help="simulated s per case (default: the scene's run)")
    length.add_argument("--steps", type=int, default=0, help="steps per case instead of a time")
    p.add_argument("--settle", type=float, default=None, help="s of settling first (default: the scene's run.settle)")
    p.add_argument("--out", default="sweep.csv", help="the table (CSV, one row per case; default sweep.csv)")
    p.add_argument("--work-dir", default=None, help="each case's folder: attempts, probes.csv (default: OUT_cases; "
                   "on a cluster of machines, a folder every worker sees)")
    p.add_argument("--scheduler", default=None, metavar="ADDR", help="a Dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", type=int, default=0, help="LocalCluster worker processes (default: cores / threads)")
    p.add_argument("--threads", type=int, default=1, help="solver threads per case (default 1)")
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


def label(case):
    return " ".join("%s=%s" % kv for kv in case.items()) or "(the scene)"


def write_table(path, keys, cases, rows):
    columns = ["case"] + keys + ["status", "attempts"]
    for r in rows:
        for c in r:
            if c not in columns:
                columns.append(c)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, restval="")
        w.writeheader()
        for k, (case, r) in enumerate(zip(cases, rows)):
            w.writerow(dict(r, case=k, **case))
    os.replace(tmp, path)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    import sphxr
    try:
        axes = [parse_axis(g) for g in args.grid]
        keys, cases = make_cases(axes)
        compares = load_compares(args.compare)
        window = [float(x) for x in args.mm_window.split(",")]
        scene_path = sphxr.find_scene(args.scene)
        info = sphxr.scene_info(scene_path, set=args.set)
        measured = None
        if info["dam_break_column_width"] is not None:
            mm_file = args.measured or os.path.join(sphxr.data_dir(), "martin_moyce_1952.csv")
            measured = {"front": read_series(mm_file, "front"), "height": read_series(mm_file, "height")}
    except (ValueError, OSError, sphxr.Error) as e:
        print("sphxr.sweep: error: %s" % e, file=sys.stderr)
        return 2
    has_probes = info["probe_columns"] is not None
    with open(scene_path) as f:
        scene_text = f.read()
    work_dir = os.path.abspath(args.work_dir or os.path.splitext(args.out)[0] + "_cases")
    os.makedirs(work_dir, exist_ok=True)
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

    import dask
    from distributed import Client, LocalCluster, as_completed
    dask.config.set({"distributed.scheduler.allowed-failures": args.allowed_failures})
    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        workers = args.workers or max(1, (os.cpu_count() or 1) // max(1, args.threads))
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    say = (lambda *a: None) if args.quiet else (lambda msg: print("sphxr.sweep: " + msg, file=sys.stderr, flush=True))
    say("%d case(s) of %s on %s" % (len(cases), scene_path, client.scheduler.address if args.scheduler else
                                    "a local cluster of %d worker processes" % len(cluster.workers)))
    rows = [None] * len(cases)
    futures = {}
    for k, spec in enumerate(specs):
        futures[client.submit(run_case, spec, key="sphxr-case-%03d-%s" % (k, os.urandom(4).hex()), pure=False)] = k
    done = failed = 0
    begin = time.time()
    try:
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
                rows[k] = {"status": "failed: %s: %s" % (type(e).__name__, str(e).replace("\n", " ")[:300]),
                           "attempts": attempts}
            done += 1
            ok = rows[k]["status"] == "ok"
            failed += 0 if ok else 1
            say("[%d/%d, %d failed, %.0f s] case %d %s: %s%s%s" % (
                done, len(cases), failed, time.time() - begin, k, label(cases[k]), rows[k]["status"],
                " in %.1f s" % rows[k]["wall_s"] if ok else "",
                " (attempt %d)" % rows[k]["attempts"] if rows[k].get("attempts", 1) > 1 else ""))
    except KeyboardInterrupt:
        say("interrupted: the cases not finished are reported as such")
    finally:
        for k in range(len(rows)):
            if rows[k] is None:
                rows[k] = {"status": "not finished (the sweep was interrupted)", "attempts": 0}
        write_table(args.out, keys, cases, rows)
        client.close()
        if cluster is not None:
            cluster.close()
    say("wrote %d row(s) to %s (%d failed)" % (len(rows), args.out, failed))
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    # The tasks are this module's functions by name (sphxr.sweep.run_case), not __main__'s: a worker
    # imports the installed module instead of receiving a pickled copy of this file's code.
    from sphxr import sweep

    sys.exit(sweep.main())
