#!/usr/bin/env python3
"""Why holding a particle's acceleration (activity-based reuse) is unstable: docs/reuse_history.md (the impulse hold that replaced it: docs/reuse.md).

One sound mode x'' = -w^2 x, integrated by the solver's symplectic Euler (v += a dt; x += v dt), with
the acceleration computed once and held for k = IDLE + 1 steps. Prints, per w dt and k, the k-step
map's determinant and its largest eigenvalue (per cycle and per step), and the steps a perturbation
needs to grow ten-thousand-fold; and for the alternative hold (the k steps' impulse at once, then
coasting: symplectic Euler at step k dt, stable only for k w dt < 2) its largest eigenvalue. Each map is checked against stepping the oscillator directly.

    python3 bench/hold_stability.py
"""
import math

import numpy as np


def checked(m, cycle):
    """m, after checking each column against `cycle` (one reuse cycle stepped directly from (x0, u0))."""
    for x0, u0 in ((1.0, 0.0), (0.0, 1.0)):
        x, u = cycle(x0, u0)
        assert abs(x - (m[0, 0] * x0 + m[0, 1] * u0)) < 1e-12 and abs(u - (m[1, 0] * x0 + m[1, 1] * u0)) < 1e-12
    return m


def hold_map(wdt, k):
    """The k-step map of (x, u = v dt) when a = -w^2 x0 is held for k steps."""
    w2 = wdt * wdt

    def cycle(x, u):
        a = -w2 * x
        for _ in range(k):
            u += a
            x += u
        return x, u

    return checked(np.array([[1.0 - w2 * k * (k + 1) / 2.0, float(k)], [-k * w2, 1.0]]), cycle)


def impulse_map(wdt, k):
    """The alternative: the k steps' impulse k dt a applied at once, then k steps of coasting."""
    w2 = wdt * wdt

    def cycle(x, u):
        u += k * (-w2 * x)
        return x + k * u, u

    return checked(np.array([[1.0 - k * k * w2, float(k)], [-k * w2, 1.0]]), cycle)


def coast_map(wdt, k):
    """Kick once, then drift: v += dt a at the computing step, then k steps of x += v dt with no force
    (the eleventh session's "coast"). Determinant 1; stable for sqrt(k) w dt < 2; the mode's frequency
    becomes about w / sqrt(k) (the particle responds as if k times heavier)."""
    w2 = wdt * wdt

    def cycle(x, u):
        u += -w2 * x
        return x + k * u, u

    return checked(np.array([[1.0 - k * w2, float(k)], [-w2, 1.0]]), cycle)


def freeze_map(wdt, k):
    """Freeze: one ordinary step at the computing step, then k - 1 steps in which the particle does not
    move at all. The k-step map is one symplectic Euler step: stable for w dt < 2, but the mode
    advances one step per k, so its frequency becomes about w / k (the calm water's clock runs k times
    slow)."""
    w2 = wdt * wdt

    def cycle(x, u):
        u += -w2 * x
        return x + u, u

    return checked(np.array([[1.0 - w2, 1.0], [-w2, 1.0]]), cycle)


def frequency_ratio(m, wdt, k):
    """The mode's frequency under map m (one k-step cycle) over its true frequency w."""
    ev = np.linalg.eigvals(m)
    if max(abs(ev)) > 1.0 + 1e-6:
        return float("nan")
    return abs(np.angle(ev[0])) / (k * wdt)


def main():
    print("| w dt | k = IDLE + 1 | determinant | max abs eigenvalue per cycle | per step | steps to grow x10^4 | impulse hold: max abs eigenvalue |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for wdt in (1.0, 0.5, 1.0 / 3.0, 0.1):
        for k in (1, 2, 4):
            m = hold_map(wdt, k)
            ev = max(abs(np.linalg.eigvals(m)))
            per_step = ev ** (1.0 / k)
            grow = f"{math.log(1e4) / math.log(per_step):.0f}" if per_step > 1.0 + 1e-12 else "never"
            imp = max(abs(np.linalg.eigvals(impulse_map(wdt, k))))
            print(f"| {wdt:.3g} | {k} | {np.linalg.det(m):.4g} | {ev:.4g} | {per_step:.4g} | {grow} | {imp:.4g} |")


    print()
    print("Holds that do not hold the acceleration (docs/reuse_history.md, eleventh session): largest |eigenvalue| per")
    print("cycle, and the mode's frequency as a fraction of the true one (nan: unstable)")
    print()
    print("| w dt | k = IDLE + 1 | coast: max abs eigenvalue | coast: frequency / w | freeze: max abs eigenvalue | freeze: frequency / w |")
    print("|---:|---:|---:|---:|---:|---:|")
    for wdt in (1.0, 0.8, 0.5):
        for k in (2, 4, 8):
            c, f = coast_map(wdt, k), freeze_map(wdt, k)
            print(f"| {wdt:.3g} | {k} | {max(abs(np.linalg.eigvals(c))):.4g} | {frequency_ratio(c, wdt, k):.3f} "
                  f"| {max(abs(np.linalg.eigvals(f))):.4g} | {frequency_ratio(f, wdt, k):.3f} |")


if __name__ == "__main__":
    main()
