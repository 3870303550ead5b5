"""Cost of the foundation operators against N (the foundation's performance targets).

Prints, for finite differences (sparse, N = 1e3 ... 1e6) and Fourier (dense,
N = 63 ... 1023), the wall time to build M, M M-dagger, the faceting + perimeter
Hessian, and one normal velocity, and the fitted exponent of time against N.

Run: ``python benchmarks/bench_foundation.py [--quick]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.energies import Faceting, Perimeter


def best_of(fn, repeat):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def measure(grid, repeat):
    c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), grid)
    E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    return {
        "M": best_of(lambda: geometry.M(c), repeat),
        "MM†": best_of(lambda: geometry.MMdagger(c), repeat),
        "Hessian": best_of(lambda: E.hessian(c), repeat),
        "V^n": best_of(lambda: E.normal_velocity(c), repeat),
    }


def table(title, grids, repeat):
    rows = []
    print(f"\n{title}")
    print(f"{'N':>9} " + " ".join(f"{k:>11}" for k in ("M", "MM†", "Hessian", "V^n")))
    for grid in grids:
        r = measure(grid, repeat)
        rows.append((grid.N, r))
        print(f"{grid.N:>9} " + " ".join(f"{v * 1e3:>9.2f}ms" for v in r.values()))
    Ns = np.array([n for n, _ in rows], dtype=float)
    print(f"{'exponent':>9} " + " ".join(
        f"{np.polyfit(np.log(Ns), np.log([r[k] for _, r in rows]), 1)[0]:>11.2f}"
        for k in rows[0][1]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes (CI smoke run)")
    args = ap.parse_args()
    fd = [1000, 10_000, 100_000] if args.quick else [1000, 10_000, 100_000, 1_000_000]
    ff = [63, 127, 255] if args.quick else [63, 127, 255, 511, 1023]
    table("FiniteDifference (scipy.sparse)", [FiniteDifference(n) for n in fd], 3)
    table("Fourier (dense)", [Fourier(n) for n in ff], 3)


if __name__ == "__main__":
    main()
