"""Cost of energy + gradient + Hessian of second-order energies against N.

Finite differences, N = 10^3 ... 10^5: the Hessian is sparse (bandwidth 2 per block), so
the cost should be O(N); the script prints the exponent p of a least-squares fit
``time ~ N^p`` (target p <= 1.15) for

* ``FunctionalizedCurvature(alpha, eta, kstar)`` (a second-order density plus the two
  faceting densities), and
* ``SecondOrderEnergy(F, dF, d2F)`` with one density that couples q, p and k,

next to ``Faceting`` for scale. A short Fourier table (dense, O(N^3)) follows.
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


if __name__ == "__main__":
    main()
