#!/usr/bin/env python3
"""Plots the cost/accuracy sweep of sphxr_bench_tradeoff.

usage: /usr/bin/python3 bench/plot_tradeoff.py [bench/results/tradeoff.csv] [docs/images/tradeoff.png]

Left: wall seconds per simulated second (log x) against the RMS relative error of the surge front
against Martin & Moyce (1952). Right: the same cost against the time-averaged mean density error.
WCSPH points (circles, solid lines) are labelled spacing/stiffness (e.g. "a/20 x1"), DFSPH points (squares,
dashed lines) spacing/density tolerance (e.g. "a/20 0.1%"), PBF points (triangles, dotted lines)
spacing/iterations per substep (e.g. "a/20 3 it"); lines join runs of one method and spacing.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def number(text):
    try:
        v = float(text)
    except (TypeError, ValueError):
        return math.nan
    return v


# Per method: its knob's label in a row, the line style, and whether the line gets one label (DFSPH's
# tolerances often give the same run) or one per point.
METHODS = {
    "wcsph": (lambda r: f"x{number(r['stiffness_factor']):g}", "o-", False),
    "dfsph": (lambda r: f"tol {number(r['density_tolerance_pct']):g} %", "s--", True),
    "pbf": (lambda r: f"{number(r.get('pbf_iterations')):g} it", "^:", False),
}
# Along each line: from the cheapest setting to the most accurate.
ORDER = {
    "wcsph": lambda r: number(r["stiffness_factor"]),
    "dfsph": lambda r: -number(r["density_tolerance_pct"]),
    "pbf": lambda r: number(r.get("pbf_iterations")),
}


def main(argv):
    src = argv[1] if len(argv) > 1 else os.path.join(ROOT, "bench", "results", "tradeoff.csv")
    dst = argv[2] if len(argv) > 2 else os.path.join(ROOT, "docs", "images", "tradeoff.png")
    with open(src, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{src}: no rows")

    quick = any(r.get("mode") == "quick" for r in rows)
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    fig.subplots_adjust(bottom=0.22, top=0.9, wspace=0.25)
    panels = [
        ("front_rms_rel", "front RMS error vs Martin & Moyce (after gate lag) [%]"),
        ("mean_density_error", "mean density error, time-averaged [%]"),
    ]
    divisors = sorted({int(r["spacing_divisor"]) for r in rows})
    methods = [m for m in METHODS if any(r.get("method", "wcsph") == m for r in rows)]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (key, label) in zip(axes, panels):
        for method in methods:
            knob, style, one_label = METHODS[method]
            for k, d in enumerate(divisors):
                runs = [r for r in rows if int(r["spacing_divisor"]) == d and r.get("method", "wcsph") == method]
                runs.sort(key=lambda r: ORDER[method](r))
                pts = [(number(r["wall_per_sim_s"]), 100.0 * number(r[key]), r) for r in runs]
                pts = [p for p in pts if math.isfinite(p[0]) and math.isfinite(p[1]) and p[0] > 0]
                if not pts:
                    continue
                colour = colours[k % len(colours)]
                fluid = int(pts[0][2]["fluid"])
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style, color=colour,
                        label=f"{method.upper()} a/{d} ({fluid:,} fluid particles)")
                if one_label:  # one label per line: settings that give the same run would print on top of each other
                    values = [knob(r) for _, _, r in pts]
                    ax.annotate(f"{method.upper()} a/{d}, {values[0]}..{values[-1]}", (pts[-1][0], pts[-1][1]),
                                textcoords="offset points", xytext=(5, -10), fontsize=7, color=colour)
                else:
                    for x, y, r in pts:
                        ax.annotate(f"a/{d} {knob(r)}", (x, y), textcoords="offset points", xytext=(5, 4), fontsize=7,
                                    color=colour)
        ax.set_xscale("log")
        ax.margins(x=0.2, y=0.15)
        ax.set_xlabel("wall seconds per simulated second (CPU, log scale)")
        ax.set_ylabel(label)
        if key == "mean_density_error":
            ax.set_yscale("log")
        else:
            ax.set_ylim(0, ax.get_ylim()[1] * 1.1)
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=3, frameon=False)
    r0 = rows[0]
    title = (f"sphxr dam break (Martin & Moyce 1952): cost vs accuracy, WCSPH (stiffness), DFSPH (density tolerance), "
             f"PBF (iterations) — "
             f"{r0.get('cpu_model', '?')}, solver threads: {r0.get('threads', '?')}")
    if quick:
        title += "\n--quick smoke run: 2 configurations to t = 0.05 s, front error over T <= 0.93 only (not a result)"
    fig.suptitle(title, fontsize=10)
    fig.savefig(dst, dpi=110)
    print(f"wrote {dst}")


if __name__ == "__main__":
    main(sys.argv)
