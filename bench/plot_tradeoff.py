#!/usr/bin/env python3
"""Plots the cost/accuracy sweep of sphxr_bench_tradeoff.

usage: /usr/bin/python3 bench/plot_tradeoff.py [bench/results/tradeoff.csv] [docs/images/tradeoff.png]

Left: wall seconds per simulated second (log x) against the RMS relative error of the surge front
against Martin & Moyce (1952). Right: the same cost against the time-averaged mean density error.
Each point is labelled spacing/stiffness (e.g. "a/20 x1"); lines join runs of the same spacing.
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


def main(argv):
    src = argv[1] if len(argv) > 1 else os.path.join(ROOT, "bench", "results", "tradeoff.csv")
    dst = argv[2] if len(argv) > 2 else os.path.join(ROOT, "docs", "images", "tradeoff.png")
    with open(src, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{src}: no rows")

    quick = any(r.get("mode") == "quick" for r in rows)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    panels = [
        ("front_rms_rel", "surge front RMS relative error vs Martin & Moyce [%]"),
        ("mean_density_error", "mean density error, time-averaged [%]"),
    ]
    divisors = sorted({int(r["spacing_divisor"]) for r in rows})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (key, label) in zip(axes, panels):
        for k, d in enumerate(divisors):
            runs = sorted((r for r in rows if int(r["spacing_divisor"]) == d), key=lambda r: number(r["stiffness_factor"]))
            pts = [(number(r["wall_per_sim_s"]), 100.0 * number(r[key]), r) for r in runs]
            pts = [p for p in pts if math.isfinite(p[0]) and math.isfinite(p[1]) and p[0] > 0]
            if not pts:
                continue
            colour = colours[k % len(colours)]
            fluid = int(pts[0][2]["fluid"])
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=colour,
                    label=f"a/{d} ({fluid:,} fluid particles)")
            for x, y, r in pts:
                ax.annotate(f"a/{d} x{number(r['stiffness_factor']):g}", (x, y), textcoords="offset points",
                            xytext=(5, 4), fontsize=8, color=colour)
        ax.set_xscale("log")
        ax.margins(x=0.2, y=0.15)
        ax.set_xlabel("wall seconds per simulated second (CPU, log scale)")
        ax.set_ylabel(label)
        ax.set_ylim(0, ax.get_ylim()[1] * 1.1)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3, frameon=False)
    r0 = rows[0]
    title = (f"sphxr dam break (Martin & Moyce 1952): cost vs accuracy, spacing a/N x stiffness factor — "
             f"{r0.get('cpu_model', '?')}, solver threads: {r0.get('threads', '?')}")
    if quick:
        title += "\n--quick smoke run: 2 configurations to t = 0.05 s, front error over T <= 0.93 only (not a result)"
    fig.suptitle(title, fontsize=10)
    fig.savefig(dst, dpi=110)
    print(f"wrote {dst}")


if __name__ == "__main__":
    main(sys.argv)
