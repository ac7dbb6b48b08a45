#!/usr/bin/python3
"""The wall pressure at P1 and P2 of Buchner (2002)'s dam break against the simulation.

Usage: plot_buchner.py OUT.png SIM.csv[:LABEL] ...
SIM.csv: the probes tests/validation/buchner_test.cpp writes (buchner_<density>.csv in the test's
working directory: t sqrt(g/H), p1/(rho g H), p2/(rho g H), 5 ms averages)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DATA = "tests/data/buchner_2002_%s.csv"


def read(path, columns):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip() or line[0].isalpha():
                continue
            rows.append([float(v) for v in line.split(",")[:columns]])
    return list(zip(*rows))


def main():
    out, sims = sys.argv[1], sys.argv[2:]
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for k, (ax, name) in enumerate(zip(axes, ("p1", "p2"))):
        t, p = read(DATA % name, 2)
        ax.plot(t, p, "k.", markersize=3, label="Buchner (2002), measured")
        for spec in sims:
            path, _, label = spec.partition(":")
            cols = read(path, 3)
            ax.plot(cols[0], cols[1 + k], linewidth=1, label=label or path)
        ax.set_ylabel("%s: p / (rho g H)" % name.upper())
        ax.set_xlim(0, 7.5)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[1].set_xlabel("t sqrt(g / H)")
    fig.suptitle("Dam break, H = 0.6 m, H/dx = 40: wall pressure (5 ms averages)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
