#!/usr/bin/python3
"""The Martin & Moyce dam break from Python, cell by cell (docs/user/python.md).

Run it as a script (`/usr/bin/python3 dam_break.py`, `--quick` for a coarse 10-second version), or cell
by cell in an editor that knows `# %%` cells (VS Code, Spyder, Jupyter's jupytext). It needs the sphxr
module on the path: installed (`cmake --install`), or PYTHONPATH=build/python in the source tree.
"""
# %% A run of a shipped scene, found by name as `sphxr --scene dam_break` finds it
import argparse
import os

import numpy as np

import sphxr

args = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
args.add_argument("--quick", action="store_true", help="a/8 instead of a/14, to T = 1.6")
args = args.parse_known_args()[0]  # (a notebook's kernel passes its own arguments)

a = 0.05715  # the column's width (m): the scene's probe.dam_break_column_width
divisor = 8 if args.quick else 14
run = sphxr.Run("dam_break", set={"spacing": a / divisor, "method": "dfsph", "density_tolerance": 0.1},
                 threads=1 if args.quick else 0)  # 0: every core
print(run)
print("parameters:", {k: run.parameters()[k] for k in ("method", "spacing", "stiffness", "density_tolerance")})

# %% Step by simulated time; the GIL is released meanwhile (Ctrl-C stops after the step in progress)
T_end = 1.6 if args.quick else 3.3  # T = t sqrt(2 g / a)
t_end = T_end / np.sqrt(2 * 9.81 / a)
run.run_to(t_end)
s = run.summary()
print("%d steps to t = %.3f s in %.2f s of wall time; mean density error %.3f %%" %
      (s["steps"], s["time"], s["wall_seconds"], 100 * s["mean_density_error"]))

# %% The fields, as NumPy arrays in particle-id order
positions, velocities = run.positions(), run.velocities()
speed = np.linalg.norm(velocities, axis=1)
print("%d particles; the fastest at x = %.3f m moves %.2f m/s" % (len(positions), positions[speed.argmax(), 0],
                                                                   speed.max()))

# %% The surge front against the experiment (Martin & Moyce 1952, shipped with sphxr)
front = run.dam_break()  # T, Z = front / a, H = height / 2a, after every step
with open(os.path.join(sphxr.data_dir(), "martin_moyce_1952.csv")) as f:
    rows = [line.strip().split(",") for line in f if line.strip() and not line.startswith("#")][1:]
measured = np.array([(float(t), float(z)) for series, t, z in rows if series == "front" and float(t) <= front["T"][-1]])
print("   T   Z measured  Z simulated")
for T, Z in measured:
    print("%5.2f  %10.2f  %11.2f" % (T, Z, np.interp(T, front["T"], front["Z"])))
rel = np.interp(measured[:, 0], front["T"], front["Z"]) / measured[:, 1] - 1
print("front RMS deviation %.1f %% over %d points" % (100 * np.sqrt(np.mean(rel ** 2)), len(rel)))

# %% Save the state and continue from it in a second run
run.save_state("dam_break.state")
later = sphxr.Run("dam_break", set={"spacing": a / divisor, "method": "dfsph", "density_tolerance": 0.1},
                  load_state="dam_break.state")
later.step(10)
print("continued from step %d to step %d (t = %.4f s)" % (run.steps, later.steps, later.time))

# %% A plot, where matplotlib is installed (Debian's python3-matplotlib)
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
if plt is not None:
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(front["T"], front["Z"], label="sphxr (a/%d, DFSPH)" % divisor)
    ax.plot(measured[:, 0], measured[:, 1], "o", label="Martin & Moyce 1952")
    ax.set_xlabel("T = t sqrt(2g/a)")
    ax.set_ylabel("Z = front / a")
    ax.legend()
    fig.tight_layout()
    fig.savefig("dam_break_front.png", dpi=100)
    print("wrote dam_break_front.png")
