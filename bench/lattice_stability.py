#!/usr/bin/env python3
"""Is a particle lattice a stable rest state of our SPH? docs/physics.md, "Why still water rattles".

Builds a periodic lattice (simple cubic, body-centred or face-centred cubic, at the number density of
the simple cubic lattice of spacing dx), scales it so that its summation density is rho0 (1 + c), and
computes the Hessian of the SPH energy E = sum_i m e(rho_i) (e' = p / rho^2, Tait with the solver's
stiffness and exponent) by central differences of the solver's pressure force
a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) gradW_ij (support `--support` spacings; the solver's cubic
spline, or with `--kernel wendland` the Wendland C2 kernel, which the solver does not use).
A negative eigenvalue is a displacement pattern along which the force pushes the particles further
away: the lattice is not a rest state, and still water started on it rearranges. The growth rate of
that pattern is sqrt(-eigenvalue). Three zero eigenvalues are the rigid translations.

    /usr/bin/python3 bench/lattice_stability.py [--support 2.0] [--compression 0.0025] [--cells 5]
        [--background PA] [--kernel cubic|wendland] [sc|bcc|fcc ...]

Needs numpy (Debian: python3-numpy). ~1 s for 125 particles, ~1 min for 500.
"""
import argparse
import math

import numpy as np

B, GAMMA, RHO0, DX = 57000.0, 7.0, 1000.0, 0.01  # tank_rest.json
BASIS = {"sc": [(0, 0, 0)], "bcc": [(0, 0, 0), (0.5, 0.5, 0.5)],
         "fcc": [(0, 0, 0), (0.5, 0.5, 0), (0.5, 0, 0.5), (0, 0.5, 0.5)]}


class Sph:
    def __init__(self, support, background=0.0, kernel="cubic"):
        self.background = background
        self.kernel = kernel
        self.H = support * DX
        self.sigma = (21.0 / (2.0 * math.pi) if kernel == "wendland" else 8.0 / math.pi) / self.H ** 3
        self.m = RHO0 * DX ** 3

    def w(self, r):
        q = r / self.H
        if self.kernel == "wendland":  # (1 - q)^4 (1 + 4q)
            return self.sigma * np.clip(1.0 - q, 0.0, None) ** 4 * (1.0 + 4.0 * q)
        inner = 6.0 * (q ** 3 - q ** 2) + 1.0
        outer = 2.0 * np.clip(1.0 - q, 0.0, None) ** 3
        return self.sigma * np.where(q < 1.0, np.where(q <= 0.5, inner, outer), 0.0)

    def dw(self, r):
        q = r / self.H
        if self.kernel == "wendland":
            return self.sigma / self.H * (-20.0 * q) * np.clip(1.0 - q, 0.0, None) ** 3
        inner = 18.0 * q ** 2 - 12.0 * q
        outer = -6.0 * np.clip(1.0 - q, 0.0, None) ** 2
        return self.sigma / self.H * np.where(q < 1.0, np.where(q <= 0.5, inner, outer), 0.0)

    def pairs(self, x, box):
        d = x[:, None, :] - x[None, :, :]
        d -= box * np.round(d / box)  # nearest periodic image (box > 2 H checked by the caller)
        return d, np.sqrt((d ** 2).sum(-1))

    def density(self, x, box):
        _, r = self.pairs(x, box)
        return self.m * self.w(r).sum(1)

    def accel(self, x, box):
        d, r = self.pairs(x, box)
        rho = self.m * self.w(r).sum(1)
        p = B * ((rho / RHO0) ** GAMMA - 1.0) - self.background  # compressed: no clamp at 0 (unless --background)
        term = p / rho ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            factor = np.where(r > 0.0, self.dw(r) / r, 0.0)
        coef = self.m * (term[:, None] + term[None, :]) * factor
        return -(coef[:, :, None] * d).sum(1)


def lattice(kind, cells, a):
    pts = [(i + b[0], j + b[1], k + b[2]) for i in range(cells) for j in range(cells) for k in range(cells)
           for b in BASIS[kind]]
    return np.array(pts, dtype=float) * a, cells * a


def analyse(kind, support, compression, cells, background, kernel):
    sph = Sph(support, background, kernel)
    a = len(BASIS[kind]) ** (1.0 / 3.0) * DX  # the simple cubic lattice's number density
    x, box = lattice(kind, cells, a)
    if box <= 2.0 * sph.H:
        raise SystemExit(f"{kind}: {cells} cells ({box / DX:.2f} spacings) are not wider than twice the support")
    scale = (sph.density(x, box).mean() / (RHO0 * (1.0 + compression))) ** (1.0 / 3.0)
    x, box = lattice(kind, cells, a * scale)
    rho = sph.density(x, box)
    residual = np.abs(sph.accel(x, box)).max()
    n = len(x)
    hessian = np.zeros((3 * n, 3 * n))
    eps = 1e-7  # m
    for i in range(n):
        for c in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, c] += eps
            xm[i, c] -= eps
            hessian[:, 3 * i + c] = -(sph.accel(xp, box) - sph.accel(xm, box)).reshape(-1) / (2.0 * eps)
    hessian = 0.5 * (hessian + hessian.T)
    ev = np.linalg.eigvalsh(hessian)
    negative = ev[ev < -1.0]
    growth = math.sqrt(-ev[0]) if ev[0] < -1.0 else 0.0
    soft = ev[3] if len(negative) == 0 else float("nan")
    print(f"| {kind} | {kernel} | {support:g} | {compression * 100:.2f} % | {n} | {rho.mean() / RHO0 - 1:+.5f} | {residual:.1e} | "
          f"{len(negative)} of {3 * n} | {growth:.1f} | {soft:.0f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("kinds", nargs="*", default=["sc", "bcc", "fcc"])
    ap.add_argument("--support", type=float, action="append", help="support radius in spacings (repeatable; default 2.0)")
    ap.add_argument("--compression", type=float, default=0.0025, help="rho/rho0 - 1 of the lattice (default 0.0025)")
    ap.add_argument("--background", type=float, default=0.0,
                    help="Pa subtracted from every pressure (above the Tait pressure: a lattice under tension)")
    ap.add_argument("--cells", type=int, default=0, help="cubic cells per axis (default: 6 sc, 4 bcc, 4 fcc)")
    ap.add_argument("--kernel", choices=["cubic", "wendland"], default="cubic",
                    help="cubic: the solver's cubic spline (default); wendland: Wendland C2, for comparison")
    args = ap.parse_args()
    print("| lattice | kernel | support (dx) | compression | particles | rho/rho0 - 1 | max |a| at rest (m/s^2) | negative eigenvalues | "
          "fastest growth (1/s) | softest non-zero eigenvalue (1/s^2) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for support in args.support or [2.0]:
        for kind in args.kinds:
            cells = args.cells or {"sc": 6, "bcc": 4, "fcc": 4}[kind]
            analyse(kind, support, args.compression, cells, args.background, args.kernel)


if __name__ == "__main__":
    main()
