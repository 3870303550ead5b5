"""Shared test utilities: accurate reference quantities and convergence fits."""

import numpy as np

from qsa import Curve, Fourier


def fitted_order(Ns, errors):
    """Slope p of log(error) ~ -p log(N) (least squares)."""
    return -np.polyfit(np.log(np.asarray(Ns, float)), np.log(np.asarray(errors, float)), 1)[0]


def trillium(N_or_grid, amp=0.2, lobes=3, kind=Fourier):
    grid = kind(N_or_grid) if isinstance(N_or_grid, int) else N_or_grid
    return Curve.polar(lambda t: 1 + amp * np.cos(lobes * t), grid)


def skew_curve(grid):
    """A smooth closed curve with no symmetry."""
    return Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t) + 0.1 * np.sin(2 * t + 0.3), grid)


def exact_closure(kfun, gfun, theta0=0.0, nf=401, ng=800):
    """C(U) for analytic (kappa(s), g(s)) on [0,1), accurate off the closed manifold.

    theta = theta0 + int_0^s kappa g: a linear part plus a periodic part computed
    spectrally on a fine grid; the non-periodic integrals use Gauss-Legendre.
    """
    grid = Fourier(nf)
    f = kfun(grid.s) * gfun(grid.s)
    mean = f.mean()
    P = grid.cumulative(f - mean)
    x, w = np.polynomial.legendre.leggauss(ng)
    x, w = 0.5 * (x + 1), 0.5 * w
    theta = theta0 + mean * x + grid.interpolate(P, x)
    gx = gfun(x)
    return np.array([w @ (np.cos(theta) * gx), w @ (np.sin(theta) * gx), mean - 2 * np.pi])


def inner(c, a, b):
    """<a, b> = int a b dsigma on stacked (2N,) or nodal (N,) vectors."""
    w = c.dsigma
    if a.shape[0] == 2 * c.N:
        w = np.concatenate([w, w])
    return float(np.sum(a * b * w))
