"""Cost of the length / area constraints: polish, constrained spectrum, constrained flow.

* ``polish`` of the 2-D vesicle (Canham-Helfrich, fixed length 2 pi and area 0.9 pi)
  from an ellipse: the constraints add two Newton unknowns and two dense rows; the
  area enters only through its exact gradient (O(N) per step on finite differences).
* ``spectrum(..., k=6, constraints=[FixedLength()])`` of the pressurized ring
  (``CanhamHelfrich + Pressure``): the area Hessian is dense (O(N^2) memory, O(N^3)
  to assemble), so on finite-difference grids the factored shift-invert is no longer
  O(N); this table shows where that starts to cost.
* ``solve_flow`` of the vesicle to t = 0.1 with both constraints (CHA with A0 = 0).

Prints one table per task: grid, N, seconds, and the task's accuracy figure. Timings
on a shared machine are noisy; re-run when it is quiet.

Run: ``python benchmarks/bench_constraints.py``.
"""

from __future__ import annotations

import time

import numpy as np

from qsa import Curve, FiniteDifference, Fourier
from qsa.constraints import FixedArea, FixedLength
from qsa.energies import CanhamHelfrich, Pressure
from qsa.equilibria import polish
from qsa.flows import CHA, solve_flow
from qsa.spectra import spectrum

VESICLE = [FixedLength(2 * np.pi), FixedArea(0.9 * np.pi)]


def ellipse(grid, a=1.25, b=0.8):
    return Curve.polar(lambda t: a * b / np.sqrt((b * np.cos(t)) ** 2 + (a * np.sin(t)) ** 2),
                       grid)


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def bench_polish(grids):
    print("polish: vesicle (nu = 0.9) from an ellipse")
    print(f"{'grid':>22} {'steps':>6} {'seconds':>9} {'rel. residual':>14}")
    for grid in grids:
        r, dt = timed(lambda grid=grid: polish(CanhamHelfrich(1.0), ellipse(grid),
                                             constraints=VESICLE))
        print(f"{grid!r:>22} {r.n_newton:>6} {dt:>9.3f} {r.relative_residual:>14.2e}")


def bench_spectrum(grids, p=-1.0):
    print(f"spectrum(k=6): ring CanhamHelfrich(1) + Pressure({p}) at fixed length, R = 1")
    print(f"{'grid':>22} {'seconds':>9} {'n_unstable':>11} {'max |lambda_2 / exact - 1|':>28}")
    exact = -3 * (3 + p)  # lambda_2 = -(k^2 - 1)(eps (k^2 - 1)/R^4 + p/R), k = 2
    for grid in grids:
        c = Curve.circle(1.0, grid)
        s, dt = timed(lambda c=c: spectrum(CanhamHelfrich(1.0) + Pressure(p), c, k=6,
                                           constraints=[FixedLength()]))
        lam2 = s.eigenvalues[~s.is_kernel]
        lam2 = lam2[np.argsort(np.abs(lam2 - exact))][:2]
        print(f"{grid!r:>22} {dt:>9.3f} {s.n_unstable:>11} "
              f"{np.abs(lam2 / exact - 1).max():>28.2e}")


def bench_flow(Ns):
    print("solve_flow: vesicle flow to t = 0.1, fixed length and area (tol 1e-5)")
    print(f"{'N':>6} {'steps':>6} {'seconds':>9} {'|dA| / A':>10} {'|dL| / L':>10}")
    x, y = ellipse(Fourier(257)).positions()
    for N in Ns:
        res, dt = timed(lambda N=N: solve_flow(CHA(eps=1.0, beta=0.0, rho=1.0), (x, y), 0.1,
                                               N=N, tol=1e-5,
                                               constraints=[FixedLength(), FixedArea()]))
        A, L = res.areas(), res.length
        print(f"{N:>6} {res.n_steps:>6} {dt:>9.3f} {np.abs(A - A[0]).max() / A[0]:>10.1e} "
              f"{np.abs(L - L[0]).max() / L[0]:>10.1e}")


def main():
    bench_polish([Fourier(65), Fourier(257), FiniteDifference(256), FiniteDifference(1024)])
    print()
    bench_spectrum([Fourier(65), Fourier(257), FiniteDifference(256), FiniteDifference(1024)])
    print()
    bench_flow([128, 512])


if __name__ == "__main__":
    main()
