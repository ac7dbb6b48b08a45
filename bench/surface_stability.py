#!/usr/bin/env python3
"""Is still water's free surface a rest state of our SPH? docs/physics.md, "Ninth session".

bench/lattice_stability.py asks whether an infinite lattice is a rest state. This asks the same of a
slab with a free surface under gravity: a simple cubic lattice, periodic in x and z (`--cells` per
axis), `--fixed` layers held in place at the bottom (the deep water below) and `--free` layers above
them whose top layer is the free surface. The free layers' heights are first relaxed to equilibrium
(gravity against the pressure; by symmetry each layer stays flat), then the Hessian of the SPH energy
over the free particles' positions is taken by central differences of the solver's pressure force
a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) gradW_ij - g, with the Tait pressure clamped from below at
-`--pmin` Pa (0: the solver's clamp, no tension). A negative eigenvalue is a pattern of displacements
that the force amplifies; the script reports how the softest one is spread over the free layers.

The particle mass is rho0 / sum_j W_j over the rest lattice (consistent: the interior is at rho0),
and with `--gradfix` the kernel gradient is scaled so that -sum_j V x_j dW/dx = 1 on the lattice.
`--minimise` then looks for a true rest state nearby: FIRE (Bitzek et al. 2006) from the lattice with
every free particle displaced by up to +-`--noise` spacings, until max |a| < 1e-5 m/s^2; it reports
how far the particles went and the Hessian's lowest eigenvalues there.

    /usr/bin/python3 bench/surface_stability.py [--kernel wendland|cubic] [--support 2.0] [--pmin 0]
        [--gradfix] [--cells 5] [--free 5] [--fixed 2] [--minimise [--noise 0.01]]

Needs numpy (Debian: python3-numpy). ~5 s; --minimise ~1-2 min.
"""
import argparse
import math

import numpy as np

from lattice_stability import B, DX, GAMMA, RHO0, Sph

G = 9.81


class Slab:
    def __init__(self, args):
        self.sph = Sph(args.support, 0.0, args.kernel)
        self.pmin = args.pmin
        self.cells, self.fixed, self.free = args.cells, args.fixed, args.free
        self.layers = self.fixed + self.free
        self.width = self.cells * DX
        # The consistent mass and the gradient scale, from a periodic lattice wider than the support.
        n = int(math.ceil(2.0 * args.support)) + 3
        pts = np.array([(i, j, k) for i in range(n) for j in range(n) for k in range(n)], float) * DX
        d = pts[0] - pts
        d -= n * DX * np.round(d / (n * DX))
        r = np.sqrt((d ** 2).sum(1))
        self.lattice_sum = self.sph.w(r).sum()
        self.sph.m = RHO0 / self.lattice_sum
        with np.errstate(invalid="ignore", divide="ignore"):
            dwx = np.where(r > 0.0, self.sph.dw(r) / r, 0.0) * d[:, 0]
        # sum_j V (x_j - x_0) dW_0j/dx_0 with V = 1 / lattice sum (d = x_0 - x_j): 1 for an exact gradient
        moment = -(d[:, 0] * dwx).sum() / self.lattice_sum
        self.grad_scale = 1.0 / moment if args.gradfix else 1.0
        self.moment = moment
        self.nfixed = self.fixed * self.cells ** 2

    def positions(self, heights):
        c = self.cells
        return np.array([(i * DX, heights[l], k * DX) for l in range(self.layers) for i in range(c) for k in range(c)])

    def accel(self, x):
        d = x[:, None, :] - x[None, :, :]
        for axis in (0, 2):  # periodic in x and z
            d[:, :, axis] -= self.width * np.round(d[:, :, axis] / self.width)
        r = np.sqrt((d ** 2).sum(-1))
        rho = self.sph.m * self.sph.w(r).sum(1)
        p = np.maximum(B * ((rho / RHO0) ** GAMMA - 1.0), -self.pmin)
        term = p / rho ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            factor = np.where(r > 0.0, self.sph.dw(r) / r, 0.0) * self.grad_scale
        a = -((self.sph.m * (term[:, None] + term[None, :]) * factor)[:, :, None] * d).sum(1)
        a[:, 1] -= G
        return a, rho, p

    def relax_heights(self):
        """Damped 1D dynamics of the free layers' heights (each layer stays flat by symmetry)."""
        h = np.arange(self.layers, dtype=float) * DX
        v = np.zeros(self.layers)
        per = self.cells ** 2
        for _ in range(100000):
            a = self.accel(self.positions(h))[0][:, 1].reshape(self.layers, per).mean(1)
            a[: self.fixed] = 0.0
            v = 0.9 * v + a * 2e-4
            h += v * 2e-4
            if np.abs(a).max() < 1e-5 and np.abs(v).max() < 1e-9:
                break
        return h

    def hessian(self, x):
        nf = len(x) - self.nfixed
        hess = np.zeros((3 * nf, 3 * nf))
        eps = 1e-8  # m
        for i in range(nf):
            for c in range(3):
                xp, xm = x.copy(), x.copy()
                xp[self.nfixed + i, c] += eps
                xm[self.nfixed + i, c] -= eps
                hess[:, 3 * i + c] = -(self.accel(xp)[0][self.nfixed:] - self.accel(xm)[0][self.nfixed:]).reshape(-1) / (2 * eps)
        return 0.5 * (hess + hess.T)

    def report_modes(self, x, label):
        ev, vec = np.linalg.eigh(self.hessian(x))
        negative = int((ev < -1.0).sum())
        line = f"{label}: {negative} of {len(ev)} eigenvalues negative; lowest {', '.join(f'{e:.0f}' for e in ev[:4])} /s^2"
        if negative:
            w = (vec[:, 0].reshape(-1, 3) ** 2)
            per = self.cells ** 2
            layers = [w[l * per:(l + 1) * per].sum() for l in range(self.free)]
            line += (f"; fastest growth {math.sqrt(-ev[0]):.1f} /s; the softest mode's weight per free layer, bottom to top: "
                     + " ".join(f"{x:.2f}" for x in layers) + f" ({w[:, [0, 2]].sum():.0%} sideways)")
        print(line)


def fire(slab, x, noise, seed=1):
    """FIRE (Bitzek et al. 2006) on the free particles until max |a| < 1e-5 m/s^2."""
    rng = np.random.default_rng(seed)
    x = x.copy()
    x[slab.nfixed:] += rng.uniform(-noise, noise, x[slab.nfixed:].shape) * DX
    v = np.zeros_like(x)
    dt, dt_max, alpha, n_plus = 5e-5, 3e-4, 0.1, 0
    for it in range(200000):
        f = slab.accel(x)[0]
        f[: slab.nfixed] = 0.0
        if np.abs(f).max() < 1e-5:
            return x, it
        if (f * v).sum() > 0.0:
            v = (1.0 - alpha) * v + alpha * f * np.linalg.norm(v) / (np.linalg.norm(f) + 1e-30)
            n_plus += 1
            if n_plus > 5:
                dt, alpha = min(1.1 * dt, dt_max), 0.99 * alpha
        else:
            v[:], dt, alpha, n_plus = 0.0, 0.5 * dt, 0.1, 0
        v += f * dt
        v[: slab.nfixed] = 0.0
        x += v * dt
    return x, -1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--kernel", choices=["cubic", "wendland"], default="wendland")
    ap.add_argument("--support", type=float, default=2.0, help="support radius in spacings (default 2.0)")
    ap.add_argument("--pmin", type=float, default=0.0, help="tension allowed, Pa (default 0: the solver's clamp)")
    ap.add_argument("--gradfix", action="store_true", help="scale the gradient so that the lattice's moment is 1")
    ap.add_argument("--cells", type=int, default=5, help="lattice cells per periodic axis (default 5)")
    ap.add_argument("--free", type=int, default=5, help="free layers, the top one the surface (default 5)")
    ap.add_argument("--fixed", type=int, default=2, help="layers held in place below them (default 2)")
    ap.add_argument("--minimise", action="store_true", help="also look for a rest state nearby (FIRE)")
    ap.add_argument("--noise", type=float, default=0.01, help="--minimise: start displacement, spacings (default 0.01)")
    args = ap.parse_args()
    if args.cells * DX <= 2.0 * args.support * DX:
        raise SystemExit(f"--cells {args.cells}: the periodic width must exceed twice the support ({2 * args.support:g} spacings)")

    slab = Slab(args)
    print(f"{args.kernel} at {args.support:g} dx: lattice sum {slab.lattice_sum * DX ** 3:.5f}/dx^3, m = "
          f"{slab.sph.m / (RHO0 * DX ** 3):.5f} rho0 dx^3, gradient moment {slab.moment:.4f} (scale {slab.grad_scale:.4f}); "
          f"tension to -{args.pmin:g} Pa; {args.cells}x{args.cells} periodic, {args.fixed} fixed + {args.free} free layers")
    h = slab.relax_heights()
    x = slab.positions(h)
    _, rho, p = slab.accel(x)
    per = args.cells ** 2
    print("| layer (0 = bottom) | height (dx) | rho/rho0 | p (Pa) |")
    print("|---:|---:|---:|---:|")
    for layer in range(slab.layers):
        s = slice(layer * per, (layer + 1) * per)
        tag = " (fixed)" if layer < args.fixed else (" (surface)" if layer == slab.layers - 1 else "")
        print(f"| {layer}{tag} | {h[layer] / DX:.4f} | {rho[s].mean() / RHO0:.5f} | {p[s].mean():.1f} |")
    slab.report_modes(x, "the lattice at equilibrium")
    if args.minimise:
        xm, its = fire(slab, x, args.noise)
        if its < 0:
            print("FIRE did not converge in 200,000 iterations")
            return
        moved = np.sqrt(((xm - x)[slab.nfixed:] ** 2).sum(1)).reshape(args.free, per) / DX
        print(f"FIRE converged in {its} iterations; distance from the lattice (dx) per free layer, bottom to top: mean "
              + " ".join(f"{m:.3f}" for m in moved.mean(1)) + ", max " + " ".join(f"{m:.3f}" for m in moved.max(1)))
        slab.report_modes(xm, "the rest state found")


if __name__ == "__main__":
    main()
