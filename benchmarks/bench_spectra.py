"""Cost of ``qsa.spectra.spectrum``: dense full spectrum of J, sparse shift-invert.

* Fourier N = 1023: all eigenvalues of ``J`` (dense, symmetric standard form), once
  without and once with the two-resolution spurious-mode check (second solve at
  N2 = 1535, eigenvalues only).
* Finite differences N = 10^5: the 20 eigenvalues of ``J`` nearest 0 (sparse LU of
  ``S - sigma I`` with a Woodbury correction for the perimeter's rank-one term,
  ARPACK in shift-invert mode).

The state is the 3-pulse equilibrium of ``Faceting(alpha=0.15, kstar=5) + Perimeter(5, L*)``
(:func:`qsa.equilibria.npulse`) sampled on each grid (FD at N = 10^3, 10^4, 10^5). Targets
(issue 4): <= 10 s each on 2 cores. Prints a table: case, N, eigenvalues, seconds
(assembly + solve), n_unstable, n_kernel, largest eigenvalue, |lambda| of the kernel.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_spectra.py``.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from qsa import FiniteDifference, Fourier
from qsa.equilibria import npulse
from qsa.spectra import spectrum


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main(alpha=0.15):
    rows = []
    eq = npulse(3, alpha, grid=Fourier(1023))
    for reject in (False, True):
        s, dt = timed(lambda r=reject: spectrum(eq.energy, eq.curve, reject_spurious=r))
        rows.append((f"Fourier dense{' +check' if reject else ''}", 1023, s, dt))
    for N in (1000, 10_000, 100_000):
        fd = npulse(3, alpha, grid=FiniteDifference(N))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s, dt = timed(lambda c=fd: spectrum(c.energy, c.curve, k=20, sigma=0.0))
        rows.append(("FD shift-invert k=20", N, s, dt))

    print(f"{'case':<24}{'N':>8}{'#eig':>6}{'time [s]':>10}{'unstable':>10}{'kernel':>8}"
          f"{'max lambda':>14}{'kernel |lambda|':>17}{'spurious':>10}{'eps|J|':>10}")
    for name, N, s, dt in rows:
        kern = np.abs(s.eigenvalues)[np.abs(s.eigenvalues) <= s.kernel_tol]
        print(f"{name:<24}{N:>8}{s.eigenvalues.size:>6}{dt:>10.2f}{s.n_unstable:>10}"
              f"{s.n_kernel:>8}{np.max(s.eigenvalues):>14.6g}"
              f"{(kern.max() if kern.size else np.nan):>17.2e}{s.spurious.size:>10}"
              f"{s.roundoff:>10.1e}")
    print("target: <= 10 s per row (2 cores). eps|J| is the round-off level of the eigenvalues:")
    print("J has order 6 (faceting), so it grows like N^6 and swamps the small eigenvalues at")
    print("large N; compare with the resolved Fourier reference below.")
    ref = npulse(3, alpha)  # the smallest Fourier grid resolving the fronts
    ev = spectrum(ref.energy, ref.curve).eigenvalues
    print(f"Fourier reference (N = {ref.curve.N}), 8 eigenvalues nearest 0:",
          np.array2string(ev[np.argsort(np.abs(ev))[:8]], precision=6))
    for name, N, s, _ in rows:
        ev = s.eigenvalues
        print(f"{name}, N={N}: ", np.array2string(ev[np.argsort(np.abs(ev))[:8]], precision=6))


if __name__ == "__main__":
    main()
