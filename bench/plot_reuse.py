#!/usr/bin/env python3
"""Draws docs/images/reuse.png from bench/results/reuse.csv (bench/reuse.cpp): speed-up of the whole step
against the deviation from the reuse-off run, one panel per scene, presets marked.
usage: plot_reuse.py bench/results/reuse.csv docs/images/reuse.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


# The presets as sim/src/params.cpp has them now (delta1, delta2, threshold, idle, accel_tolerance,
# impulse). Rows with those last two columns come from before the retired holds were removed: impulse 0
# the held acceleration, 2 live density (docs/design/impulse_hold.md); rows without them are the impulse
# hold. A
# preset row of the CSV whose parameters differ was measured under an older value of that preset and is
# drawn hollow; a sweep row with a preset's current parameters is drawn as that preset.
PRESETS = {"accurate": (0.1, 1.0, 1.6, 1, 0.0, 1), "balanced": (0.0, 1.0, 1.5, 3, 0.0, 1),
           "fast": (0.0, 1.0, 1.8, 3, 0.0, 1)}
COLOURS = {"accurate": "tab:green", "balanced": "tab:blue", "fast": "tab:red"}


def params(r):
    return (float(r["delta1"]), float(r["delta2"]), float(r["threshold"]), int(r["idle"]),
            float(r.get("accel_tolerance") or 0), int(r["impulse"]) if r.get("impulse") else 1)


def current_preset(r):
    for name, p in PRESETS.items():
        if all(abs(a - b) < 1e-6 for a, b in zip(params(r), p)):
            return name
    return None


def main():
    src, dst = sys.argv[1], sys.argv[2]
    rows = list(csv.DictReader(open(src)))
    # Each scene's deviation column and the targets for `balanced`: at most that deviation, at
    # least that speed-up (drawn dashed).
    scenes = [("deep_tank", "surface_rms_spacings", "free-surface RMS vs reuse off (spacings)", 0.5, 2.0),
              ("dam_break_1m", "front_deviation", "surge-front deviation vs reuse off", 3.0, 1.3)]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, (scene, key, label, worst, least) in zip(axes, scenes):
        rs = [r for r in rows if r["scene"] == scene and r["setting"] != "off"]
        if not rs:
            ax.set_title(scene + " (no data)")
            continue
        for r in rs:
            # A log axis: runs that blew up deviate 100 times more than the rest. Zero (a run that
            # matched reuse off to the printed digit) is drawn at the axis' floor.
            x = max(float(r[key]) * (100.0 if key == "front_deviation" else 1.0), 0.01)
            # The wall-time ratio: with the impulse hold one step in IDLE + 1 is dear and the rest cheap, so
            # the median step's ratio overstates the speed-up (rows without it: the median's).
            wall = r.get("wall_speedup") or "nan"
            y = float(wall) if wall not in ("", "nan") else float(r["speedup"])
            # The work bound: the density and force stages run for the active fraction only.
            ax.plot(x, 1.0 / float(r["active_fraction"]), "_", ms=10, color="tab:purple",
                    label="1 / active fraction (work bound)" if r is rs[0] else None)
            hold = params(r)[5]
            now = current_preset(r)
            if r["setting"] in PRESETS and now != r["setting"]:  # a preset's older parameters
                ax.plot(x, y, "o", ms=9, mfc="none", color=COLOURS[r["setting"]], label="%s before" % r["setting"])
            elif now is not None:
                ax.plot(x, y, "o", ms=9, color=COLOURS[now], label=now)
            elif hold == 0:
                ax.plot(x, y, "x", ms=9, color="k", label="held acceleration (the paper's)")
            elif hold == 1:
                ax.plot(x, y, "^", ms=7, color="0.4", label="impulse hold")
            else:
                ax.plot(x, y, ".", ms=8, color="0.4", label="impulse hold, live density")
        ax.axhline(1.0, color="0.7", lw=0.8)
        ax.axhline(least, color="tab:blue", lw=0.8, ls="--")
        ax.axvline(worst, color="tab:blue", lw=0.8, ls="--", label="targets for balanced")
        ax.set_xscale("log")
        ax.set_xlabel(label + (" (%)" if key == "front_deviation" else ""))
        ax.set_ylabel("speed-up of the whole step, wall time (reuse off = 1)")
        ax.set_title("%s, %s particles" % (scene, rs[0]["fluid"]))
        handles, labels = ax.get_legend_handles_labels()
        seen = {}
        for h, l in zip(handles, labels):
            seen.setdefault(l, h)
        ax.legend(seen.values(), seen.keys(), fontsize=8, loc="best")
    fig.suptitle("Activity-based reuse: speed-up against a reuse-off solver in lock-step, and the work bound, against accuracy (%s)"
                 % rows[0]["cpu_model"], fontsize=10)
    fig.tight_layout()
    fig.savefig(dst, dpi=110)


if __name__ == "__main__":
    main()
