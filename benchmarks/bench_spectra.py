"""Slow eigenvalues at every resolution: accuracy, error estimates and cost of ``spectrum``.

The state is the 3-pulse equilibrium of ``Faceting(alpha=0.15, kstar=5) + Perimeter(5, L*)``
(:func:`qsa.equilibria.npulse`), polished on each grid (:func:`qsa.equilibria.polish`).
Reference: the smallest Fourier grid that resolves the fronts (``npulse``'s default).

Rows:

* Fourier N = 1023, the 20 eigenvalues nearest 0 (``k=20``) and all of them (``k=None``:
  the formed matrix for the fast ones, the factors near 0);
* finite differences N = 10^3, 10^4, 10^5, the 20 eigenvalues nearest 0.

Printed per row: seconds (spectrum only; the polish time separately), the unstable and
kernel counts, the largest relative error estimate among the 17 non-kernel eigenvalues
nearest 0, the largest relative difference from the reference, and ``eps |J|`` (the
round-off of the formed matrix, which the factored solve avoids). Then the FD order
fitted from the unstable pair and the breathing mode, and the eigenvalues themselves.
Targets: FD N = 10^5 <= 10 s, Fourier N = 1023 <= 10 s (2 cores).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_spectra.py``.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from qsa import FiniteDifference, Fourier
from qsa.equilibria import npulse, polish
from qsa.spectra import spectrum


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def nonkernel(s, n):
    lam, err = s.eigenvalues[~s.is_kernel], s.errors[~s.is_kernel]
    order = np.argsort(np.abs(lam), kind="stable")[:n]
    return lam[order], err[order]


def equilibrium(grid, alpha):
    eq = npulse(3, alpha, grid=grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return timed(lambda: polish(eq.energy, eq.curve))


def main(alpha=0.15, n=17):
    ref_eq = npulse(3, alpha)
    ref = spectrum(ref_eq.energy, ref_eq.curve, k=n + 3)
    ref_lam, _ = nonkernel(ref, n)
    rows = []
    fourier, tp = equilibrium(Fourier(1023), alpha)
    for k in (20, None):
        s, dt = timed(lambda k=k: spectrum(fourier.energy, fourier.curve, k=k,
                                           reject_spurious=False))
        rows.append((f"Fourier k={k}", 1023, s, dt, tp))
    for N in (1000, 10_000, 100_000):
        fd, tp = equilibrium(FiniteDifference(N), alpha)
        s, dt = timed(lambda c=fd: spectrum(c.energy, c.curve, k=20))
        rows.append(("FD k=20", N, s, dt, tp))

    print(f"3-pulse, alpha = {alpha}, kstar = 5; reference Fourier N = {ref_eq.curve.N}")
    print(f"{'case':<17}{'N':>8}{'time [s]':>10}{'polish':>8}{'unst':>6}{'kern':>6}"
          f"{'max err/|l|':>13}{'max |l-ref|/|l|':>17}{'eps|J|':>10}{'unresolved':>12}")
    for name, N, s, dt, tp in rows:
        lam, err = nonkernel(s, n)
        m = min(lam.size, ref_lam.size)
        dev = np.max(np.abs(lam[:m] - ref_lam[:m]) / np.abs(ref_lam[:m]))
        print(f"{name:<17}{N:>8}{dt:>10.2f}{tp:>8.2f}{s.n_unstable:>6}{s.n_kernel:>6}"
              f"{np.max(err / np.abs(lam)):>13.1e}{dev:>17.1e}{s.roundoff:>10.1e}"
              f"{s.unresolved.size:>12}")
    fd = [(N, s) for name, N, s, _, _ in rows if name.startswith("FD")]
    errs = [np.max(np.abs(nonkernel(s, 3)[0] - ref_lam[:3]) / np.abs(ref_lam[:3]))
            for _, s in fd]
    order = -np.log(errs[1] / errs[0]) / np.log(fd[1][0] / fd[0][0])
    print(f"FD order from the 3 slowest non-kernel eigenvalues, N = {fd[0][0]} -> {fd[1][0]}: "
          f"{order:.3f}; relative errors {', '.join(f'{e:.1e}' for e in errs)} (at N = "
          f"{fd[-1][0]} the difference is at the level of the error estimates)")
    print("targets: <= 10 s per row; eigenvalues agree with the reference to the "
          "discretization error")
    print(f"\nreference (N = {ref_eq.curve.N}), {n} non-kernel eigenvalues nearest 0 "
          "and their error estimates:")
    lam, err = nonkernel(ref, n)
    print(np.array2string(lam, precision=8, max_line_width=100))
    print(np.array2string(err, precision=1, max_line_width=100))
    print("kernel (rigid Ritz values):", np.array2string(ref.eigenvalues[ref.is_kernel],
                                                         precision=2))
    for name, N, s, _, _ in rows:
        lam, err = nonkernel(s, 6)
        print(f"{name}, N={N}: {np.array2string(lam, precision=8, max_line_width=120)}")
        print(f"{'':>{len(name) + len(str(N)) + 5}}+-{np.array2string(err, precision=1)}"
              f"  kernel {np.array2string(s.eigenvalues[s.is_kernel], precision=2)}")


if __name__ == "__main__":
    main()
