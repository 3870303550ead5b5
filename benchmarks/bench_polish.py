"""Cost of ``polish``: Newton on V^n = 0 + closure from a semi-analytic N-pulse guess.

Fourier N = 1023 (dense Jacobian, O(N^3) per step) and finite differences N = 10^4
(sparse LU with four dense borders, O(N) per step). The guess is the 3-pulse (alpha = 0.15)
of ``npulse`` perturbed by a smooth mode, so every run takes several Newton steps.
Prints a table: grid, N, steps, seconds, seconds per step, final relative residual,
|C(U)|.

Run: ``python benchmarks/bench_polish.py``.
"""

from __future__ import annotations

import time

import numpy as np

from qsa import Curve, FiniteDifference, Fourier
from qsa.equilibria import npulse
from qsa.equilibria.newton import polish


def perturbed(eq, amp=0.02):
    """A smooth 3-fold symmetric normal displacement of the nodes, ``amp`` of the radius.

    The perturbed curve is closed and simple at every N (perturbing kappa alone would
    break the closure). (Asymmetric perturbations of well-separated fronts move along
    the exponentially slow manifold of front positions, where the Newton matrix is
    nearly singular.)
    """
    c = eq.curve
    s = c.grid.s
    x, y = c.positions()
    nx, ny = c.normal()
    d = amp * c.length() / (2 * np.pi) * np.cos(6 * np.pi * s + 0.3)
    return Curve.from_positions(x + d * nx, y + d * ny, c.grid)


def run(grid, alpha=0.15, n_pulses=3):
    eq = npulse(n_pulses, alpha, grid=grid)
    guess = perturbed(eq)
    t0 = time.perf_counter()
    r = polish(eq.energy, guess)
    dt = time.perf_counter() - t0
    return r, dt


def main():
    rows = []
    for grid in (Fourier(255), Fourier(1023), FiniteDifference(1000), FiniteDifference(10_000)):
        r, dt = run(grid)
        rows.append((type(grid).__name__, grid.N, r.n_newton, dt, dt / max(r.n_newton, 1),
                     r.residual / r.residual_scale, r.closure, r.status))
    print(f"{'grid':<18}{'N':>7}{'steps':>7}{'time [s]':>11}{'s/step':>10}"
          f"{'max|Vn|/scale':>15}{'|C(U)|':>10}{'status':>8}")
    for g, N, it, dt, per, rel, clo, st in rows:
        print(f"{g:<18}{N:>7}{it:>7}{dt:>11.3f}{per:>10.3f}{rel:>15.2e}{clo:>10.1e}{st:>8}")
    print("status 0: converged to tol=1e-10; 1: converged to the round-off floor of the grid")


if __name__ == "__main__":
    main()
