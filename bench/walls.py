#!/usr/bin/env python3
"""How often the clamp behind the walls catches water, with the walls' contact force on and off
(tank.wall_contact) and under both density models, per scene: clamps per 1,000 particle-steps and the
wall that clamped most, from the headless summary. docs/design/walls.md quotes the table.

    bench/walls.py [--threads T] [--scenes dam_break,jet,dam_break_1m] [--csv FILE]

The jet is the test suite's (tests/sim/walls_clamp_test.cpp): a 0.1 m block of 1,000 particles at 5 m/s,
no gravity, c = 50 m/s, in a closed 0.6 x 0.2 x 0.2 m box, 0.1 s, at the x+ wall.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

JET = {
    "name": "jet",
    "solver": {"spacing": 0.01, "stiffness": 50.0 * 50.0 * 1000.0 / 7.0},
    "gravity": [0.0, 0.0, 0.0],
    "tank": {"min": [0, 0, 0], "max": [0.6, 0.2, 0.2], "open_top": False},
    "fluid": [{"min": [0.25, 0.05, 0.05], "max": [0.35, 0.15, 0.15], "velocity": [5.0, 0.0, 0.0]}],
    "run": {"time": 0.1},
}


def scene(name):
    if name == "jet":
        return json.loads(json.dumps(JET))
    with open(os.path.join(ROOT, "scenes", name + ".json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scenes", default="dam_break,jet,dam_break_1m")
    ap.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "walls.csv"))
    args = ap.parse_args()
    binary = os.environ.get("SPHXR", os.path.join(ROOT, "build", "app", "sphxr"))
    if not os.access(binary, os.X_OK):
        sys.exit(f"bench/walls.py: {binary} not built (./scripts/setup.sh)")
    machine = "unknown"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                machine = line.split(":", 1)[1].strip().replace(",", " ")
                break
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenes.split(","):
            for contact in (False, True):
                for density in ("summation", "delta_sph"):
                    s = scene(name)
                    s["tank"]["wall_contact"] = contact
                    s.setdefault("solver", {})["density"] = density
                    path = os.path.join(tmp, name + ".json")
                    with open(path, "w") as f:
                        json.dump(s, f)
                    out = subprocess.run([binary, "--headless", "--scene", path, "--threads", str(args.threads),
                                          "--no-progress"], capture_output=True, text=True,
                                         env=dict(os.environ, OMP_WAIT_POLICY="active"))
                    if out.returncode != 0:
                        # An unstable run is a result too: its row says where it stopped.
                        last = (out.stderr.strip().splitlines() or ["no message"])[-1]
                        stop = re.search(r"at t = ([0-9.]+) s", last)
                        row = [machine, str(args.threads), name, "on" if contact else "off", density, "", "",
                               "unstable at t = %s s" % (stop.group(1) if stop else "?"), "", "", ""]
                        print(",".join(row), flush=True)
                        rows.append(row)
                        continue
                    m = re.search(r"particles lost +(\d+) \(clamped back into the tank: (\d+) times, ([0-9.e+-]+) per "
                                  r"1,000 particle-steps(?:, most at the ([^)]+))?\)", out.stdout)
                    wall = re.search(r"in ([0-9.]+) s wall", out.stdout)
                    dam = re.search(r"surge front Z = ([0-9.]+), column height H = ([0-9.]+)", out.stdout)
                    row = [machine, str(args.threads), name, "on" if contact else "off", density, m.group(2),
                           m.group(3), m.group(4) or "", wall.group(1), dam.group(1) if dam else "",
                           dam.group(2) if dam else ""]
                    print(",".join(row), flush=True)
                    rows.append(row)
    with open(args.csv, "w") as f:
        f.write("machine,threads,scene,wall_contact,density,clamps,clamps_per_1000,most_at,wall_s,"
                "surge_front_Z,column_height_H\n")
        for row in rows:
            f.write(",".join(row) + "\n")


if __name__ == "__main__":
    main()
