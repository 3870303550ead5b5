"""Cost of energy + gradient + Hessian of second-order energies against N.

Finite differences, N = 10^3 ... 10^5: the Hessian is sparse (bandwidth 2 per block), so
the cost should be O(N); the script prints the exponent p of a least-squares fit
``time ~ N^p`` (target p <= 1.15) for

* ``FunctionalizedCurvature(alpha, eta, kstar)`` (a second-order density plus the two
  faceting densities), and
* ``SecondOrderEnergy(F, dF, d2F)`` with one density that couples q, p and k,

next to ``Faceting`` for scale. A short Fourier table (dense, O(N^3)) follows, then the
slow eigenvalues of the critical circle of ``FunctionalizedCurvature(0.1, 8.8, 4)``
(R = 1/kstar) on finite differences up to N = 64000: the unstable k = 2 pair and the
breathing mode against the closed form (:meth:`~qsa.energies.SecondOrderEnergy.circle_eigenvalues`),
with the reported error estimate and the fitted order; the order-4 Hessian block is
kept factored in the solve, so the difference is the discretization's ``h^2`` term.
Times are CPU times of this process (single-threaded BLAS), best of several repeats;
on a shared machine they are noisy, the exponent less so.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_second_order.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Faceting, FunctionalizedCurvature, SecondOrderEnergy


def coupled():
    return SecondOrderEnergy(
        F=lambda q, p, k: 0.005 * q**2 + 0.01 * q * p * k + 0.05 * p**2 + np.cosh(0.5 * k),
        dF=lambda q, p, k: (0.01 * q + 0.01 * p * k, 0.01 * q * k + 0.1 * p,
                            0.01 * q * p + 0.5 * np.sinh(0.5 * k)),
        d2F=lambda q, p, k: (0.01 + 0 * q, 0.01 * k, 0.01 * p, 0.1 + 0 * q, 0.01 * q,
                             0.25 * np.cosh(0.5 * k)))


ENERGIES = {
    "FunctionalizedCurvature": FunctionalizedCurvature(alpha=0.1, eta=1.0, kstar=5.0),
    "SecondOrderEnergy": coupled(),
    "Faceting (first order)": Faceting(alpha=0.1, kstar=5.0),
}


def state(grid):
    s = grid.s
    c = Curve.circle(1.0, grid)
    return c.with_kappa(1.0 + 0.3 * np.cos(6 * np.pi * s) + 0.1 * np.sin(4 * np.pi * s))


def time_all(energy, c, repeats):
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        energy.energy(c)
        energy.gradient(c)
        H = energy.hessian(c)
        best = min(best, time.process_time() - t0)
    return best, H


def run_fd(Ns, repeats, target=1.15):
    exponents = {}
    for name, energy in ENERGIES.items():
        print(f"\n{name}, FiniteDifference: energy + gradient + Hessian")
        print(f"{'N':>8} {'nnz(H)':>10} {'nnz/N':>7} {'cpu [ms]':>10} {'us/node':>8}")
        times = []
        for N in Ns:
            c = state(FiniteDifference(N))
            t, H = time_all(energy, c, repeats)
            times.append(t)
            print(f"{N:>8} {H.nnz:>10} {H.nnz / N:>7.1f} {1e3 * t:>10.2f} {1e6 * t / N:>8.2f}")
        p = np.polyfit(np.log(Ns), np.log(times), 1)[0]
        ok = "ok" if p <= target else "MISSED"
        print(f"fitted exponent p = {p:.3f}  (target <= {target:.2f}: {ok})")
        if len(Ns) >= 5:  # small N is dominated by fixed per-call overhead
            q = np.polyfit(np.log(Ns[-3:]), np.log(times[-3:]), 1)[0]
            print(f"exponent over the three largest N: {q:.3f}")
        exponents[name] = p
    return exponents


def run_fourier(Ns, repeats):
    print("\nFourier (dense): energy + gradient + Hessian")
    print(f"{'N':>6} " + " ".join(f"{name[:24]:>25}" for name in ENERGIES))
    for N in Ns:
        c = state(Fourier(N))
        row = [time_all(e, c, repeats)[0] for e in ENERGIES.values()]
        print(f"{N:>6} " + " ".join(f"{1e3 * t:>22.2f} ms" for t in row))


def run_spectra(Ns):
    from qsa.spectra import spectrum

    E = FunctionalizedCurvature(alpha=0.1, eta=8.8, kstar=4.0)
    R = 0.25
    lam = E.circle_eigenvalues(R, 2)
    print("\nslow eigenvalues, critical circle of FunctionalizedCurvature(0.1, 8.8, 4), "
          "finite differences, k=6 nearest 0")
    print(f"{'N':>7} {'seconds':>8} {'k=2 pair - exact':>17} {'estimate':>9} "
          f"{'k=0 - exact':>12} {'estimate':>9}")
    devs = []
    for N in Ns:
        c = Curve.circle(R, FiniteDifference(N))
        t0 = time.perf_counter()
        s = spectrum(E, c, k=6, sigma=0.0)
        dt = time.perf_counter() - t0
        row = [f"{N:>7} {dt:>8.2f}"]
        for exact in (lam[2], lam[0]):
            i = int(np.argmin(np.abs(s.eigenvalues - exact)))
            row.append(f"{s.eigenvalues[i] - exact:>17.3e} {s.errors[i]:>9.1e}")
            if exact == lam[2]:
                devs.append(abs(s.eigenvalues[i] - exact))
        print(" ".join(row))
    p = -np.polyfit(np.log(Ns[:3]), np.log(devs[:3]), 1)[0]
    print(f"fitted order of the k = 2 pair (N = {Ns[0]}..{Ns[2]}): {p:.3f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer sizes and repeats")
    args = ap.parse_args(argv)
    if args.quick:
        Ns, repeats, fourier = [1000, 10000, 100000], 2, [65, 129]
    else:
        Ns = [1000, 3000, 10000, 30000, 100000]
        repeats, fourier = 5, [65, 129, 257, 513]
    run_fd(Ns, repeats)
    run_fourier(fourier, repeats)
    run_spectra([2000, 4000, 8000] if args.quick else [2000, 4000, 8000, 16000, 32000, 64000])


if __name__ == "__main__":
    main()
