#!/usr/bin/env python3
"""Does still water's free surface hold still? Time-stepping the slab of surface_stability.py.

surface_stability.py asks whether the slab's lattice is a rest state (the Hessian). This steps it in
time, as the solver does, and measures what the hydrostatic test measures: the largest distance any
free particle moves in each `--window` seconds. The slab: a simple cubic lattice at tank_rest.json's
spacing, stiffness and viscosity, periodic in x and z (`--cells` per axis), `--fixed` layers held in
place at the bottom with their hydrostatic pressure, `--free` layers above, the top one the surface.
Free particles start displaced by up to +-`--noise` spacings; the first `--settle` seconds are damped
(velocities scaled by (1 - `--damp` dt) each step).

Two density models:
  summation   (the solver)  rho_i = sum_j m W_ij, p = B((rho/rho0)^7 - 1) clamped at 0.
  continuity  (delta-SPH)   d rho_i/dt = sum_j m (v_i - v_j).gradW_ij + delta h c D_i, with the density
              diffusion D_i = sum_j 2 (rho_ji - rho^H_ji) (-W'(r)/r) m/rho_j (Molteni & Colagrossi 2009,
              with the hydrostatic part removed as in Fourtakas et al. 2019); starts at the hydrostatic
              density; pressure clamped at -`--pmin` Pa.
Forces in both: a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) gradW_ij - g, Pi the solver's
Monaghan viscosity (alpha `--alpha`), symplectic Euler at `--dt`.

    /usr/bin/python3 bench/surface_dynamics.py [--density summation|continuity] [--delta 0.1]
        [--kernel cubic|wendland] [--time 10] [--window 0.5] [--settle 2] [--cells 5] [--free 8]

Needs numpy (Debian: python3-numpy). About 20-40 s of wall time per simulated second.
"""
import argparse
import math

import numpy as np

from lattice_stability import B, DX, GAMMA, RHO0, Sph

G = 9.81


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--density", choices=["summation", "continuity"], default="summation")
    ap.add_argument("--delta", type=float, default=0.1, help="continuity: density diffusion coefficient (default 0.1)")
    ap.add_argument("--pmin", type=float, default=0.0, help="tension allowed, Pa (default 0)")
    ap.add_argument("--kernel", choices=["cubic", "wendland"], default="cubic")
    ap.add_argument("--support", type=float, default=2.0)
    ap.add_argument("--alpha", type=float, default=0.3, help="artificial viscosity (tank_rest.json: 0.3)")
    ap.add_argument("--cells", type=int, default=5)
    ap.add_argument("--free", type=int, default=8)
    ap.add_argument("--fixed", type=int, default=2)
    ap.add_argument("--noise", type=float, default=0.01)
    ap.add_argument("--dt", type=float, default=2e-4)
    ap.add_argument("--time", type=float, default=10.0)
    ap.add_argument("--window", type=float, default=0.5)
    ap.add_argument("--settle", type=float, default=2.0)
    ap.add_argument("--damp", type=float, default=50.0, help="damping rate during the settle, 1/s")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()

    sph = Sph(args.support, 0.0, args.kernel)
    c = math.sqrt(B * GAMMA / RHO0)
    h = args.support * DX / 2.0  # the solver's smoothing length (support / 2)
    cells, layers = args.cells, args.fixed + args.free
    width = cells * DX
    top = (layers - 1) * DX
    x = np.array([(i * DX, l * DX, k * DX) for l in range(layers) for i in range(cells) for k in range(cells)])
    n = len(x)
    nfixed = args.fixed * cells * cells
    free = np.arange(n) >= nfixed
    depth = top - x[:, 1]
    rho_h = RHO0 * (1.0 + RHO0 * G * depth / B) ** (1.0 / GAMMA)  # hydrostatic Tait density
    p_fixed = RHO0 * G * depth[:nfixed]
    sph.m = RHO0 * DX ** 3
    rng = np.random.default_rng(args.seed)
    x[free] += rng.uniform(-args.noise, args.noise, (free.sum(), 3)) * DX
    v = np.zeros_like(x)
    rho = rho_h.copy()
    eps = 0.01 * h * h

    def pairs(x):
        d = x[:, None, :] - x[None, :, :]
        for axis in (0, 2):
            d[:, :, axis] -= width * np.round(d[:, :, axis] / width)
        r = np.sqrt((d ** 2).sum(-1))
        return d, r

    steps = int(round(args.time / args.dt))
    per_window = int(round(args.window / args.dt))
    settle_steps = int(round(args.settle / args.dt))
    start = x.copy()
    print(f"{args.density} density, {args.kernel} at {args.support:g} dx, alpha {args.alpha:g}"
          + (f", delta {args.delta:g}" if args.density == "continuity" else "")
          + f"; {cells}x{cells} periodic, {args.fixed} fixed + {args.free} free layers; dt {args.dt:g} s, "
          f"settle {args.settle:g} s at {args.damp:g} /s")
    print("| window end (s) | max drift (dx) | median drift (dx) | max speed (m/s) | surface rho/rho0 | deepest free layer's p / rho0 g depth |")
    print("|---:|---:|---:|---:|---:|---:|")
    for step in range(1, steps + 1):
        d, r = pairs(x)
        inside = (r < sph.H) & (r > 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            factor = np.where(inside, sph.dw(r) / r, 0.0)  # gradW_ij = factor d_ij
        vij = v[:, None, :] - v[None, :, :]
        vx = (vij * d).sum(-1)
        if args.density == "summation":
            rho = sph.m * sph.w(r).sum(1)
        else:
            # Symplectic in (rho, v): the density is advanced first, with this step's velocities, and the
            # pressure force then uses the new density (forward Euler in both would pump the sound modes).
            drho = sph.m * (vx * factor).sum(1)
            # delta-SPH: 2 (rho_j - rho_i - (rho^H_j - rho^H_i)) (-W'/r) V_j, times delta h c
            dyn = (rho[None, :] - rho[:, None]) - (rho_h[None, :] - rho_h[:, None])
            drho += args.delta * h * c * (2.0 * dyn * (-factor) * (sph.m / rho[None, :])).sum(1)
            rho = rho + args.dt * drho
            rho[:nfixed] = rho_h[:nfixed]
        p = B * ((rho / RHO0) ** GAMMA - 1.0)
        p = np.maximum(p, -args.pmin)
        p[:nfixed] = p_fixed
        rho_used = rho.copy()
        if args.density == "summation":
            rho_used[:nfixed] = rho_h[:nfixed]
        term = p / rho_used ** 2
        visc = np.where(vx < 0.0, -2.0 * args.alpha * c * h * vx / ((r ** 2 + eps) * (rho_used[:, None] + rho_used[None, :])), 0.0)
        a = -((sph.m * (term[:, None] + term[None, :] + visc) * factor)[:, :, None] * d).sum(1)
        a[:, 1] -= G
        a[~free] = 0.0
        v += args.dt * a
        if step <= settle_steps:
            v *= max(0.0, 1.0 - args.damp * args.dt)
        x += args.dt * v
        if step % per_window == 0:
            moved = np.sqrt(((x - start)[free] ** 2).sum(1)) / DX
            deep = slice(nfixed, nfixed + cells * cells)
            surf = slice(n - cells * cells, n)
            ratio = p[deep].mean() / (RHO0 * G * depth[deep].mean())
            t = step * args.dt
            tag = " (settling)" if step <= settle_steps else ""
            print(f"| {t:.1f}{tag} | {moved.max():.4f} | {np.median(moved):.4f} | {np.sqrt((v ** 2).sum(1)).max():.4f} | "
                  f"{rho[surf].mean() / RHO0:.4f} | {ratio:.3f} |", flush=True)
            start = x.copy()
            if not np.isfinite(x).all():
                print("non-finite positions: stopped")
                return


if __name__ == "__main__":
    main()
