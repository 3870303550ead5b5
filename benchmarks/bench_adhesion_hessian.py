"""Cost of the exact adhesion Hessian against N (finite differences, Table T1's kernels).

For the CHA scenario's crenellated start (A0 = 40, a = 1) at l* = 0.01 and l* = 0.1,
N = 1000 ... 10^4 (the start's corners need N >= 1000 finite-difference nodes), and
the long-range kernel l* = 1/2 (all pairs, dense form) at N = 1000 ... 1400, prints
per N: the number of interacting pairs P, the time of the exact
gradient (pairs, fields and the adjoint sweep), of assembling the Hessian, its
storage and the peak memory of the assembly (tracemalloc), one assembled product
``H @ v``, one matrix-free product, and the sparse LU of the shift-invert
saddle-point system (time and fill, short-range kernels only); then the fitted
exponent of each column against N. Sizes whose estimated memory exceeds
``--memory-budget`` are skipped (say which).

Timings are wall-clock best-of-``--repeat`` and noisy on a shared machine.

Run: ``python benchmarks/bench_adhesion_hessian.py [--quick] [--memory-budget GB]``
"""

from __future__ import annotations

import argparse
import tracemalloc

import numpy as np
import scipy.sparse.linalg as spla
from _timing import best_of

from qsa import Curve, FiniteDifference
from qsa.energies import Adhesion
from qsa.linalg import ReducedHessian

try:  # the scenarios are moving to qsa.paper
    from qsa.paper.scenarios import CHAScenario
except ImportError:
    from qsa.flows.scenarios import CHAScenario

#: bytes per interacting pair at the peak of each stage (measured at N = 10^4, l* = 0.01)
BYTES_PER_PAIR = {"derivatives": 200, "reduced": 800}
#: the saddle-point LU fills in like (pairs per node)^2 per node: beyond this many pairs
#: per node (l* = 0.1 has ~400 at N = 2400, 380 s and 1.3e8 fill) a dense LU is cheaper
LU_PAIRS_PER_NODE = 100


def peak_memory(fn):
    tracemalloc.start()
    try:
        out = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak, out


def curve_for(scenario, N):
    x, y = scenario.initial(N)
    return Curve.from_positions(x, y, FiniteDifference(N))


def measure(scenario, N, method, budget, repeat, lu):
    c = curve_for(scenario, N)
    E = Adhesion(scenario.A0, scenario.l_star, scenario.a, method=method)
    x, y = c.positions()
    from qsa.energies.adhesion import adhesion_pairs

    P = adhesion_pairs(E.kernel, x, y, method=method)[0].size
    row = {"N": N, "P": P}
    dense = method == "dense" or P > N * (N - 1) // 4
    if BYTES_PER_PAIR["derivatives"] * P > budget:
        gb = BYTES_PER_PAIR["derivatives"] * P / 1e9
        row["skip"] = f"skipped: ~{gb:.1f} GB for the pair data"
        return row
    row["gradient"], d = best_of(lambda: E.derivatives(c), repeat)
    v = np.random.default_rng(0).standard_normal(2 * N)
    row["hvp"], hv = best_of(lambda: d.hessian_vector(v), repeat)
    need = 180 * N * N if dense else BYTES_PER_PAIR["reduced"] * P
    if need > budget:
        row["skip"] = f"assembly skipped: ~{need / 1e9:.1f} GB"
        return row
    row["assemble"], H = best_of(lambda: d.hessian(), repeat)
    row["peak"], _ = peak_memory(lambda: d.hessian())
    row["form"] = "reduced" if isinstance(H, ReducedHessian) else "dense"
    row["storage"] = H.nbytes
    row["matvec"], Hv = best_of(lambda: H @ v, repeat)
    row["check"] = float(np.abs(Hv - hv).max() / np.abs(hv).max())
    if lu and isinstance(H, ReducedHessian) and P <= LU_PAIRS_PER_NODE * N:
        row["lu"], f = best_of(lambda: spla.splu(H.augmented(1.0)), 1)
        row["fill"] = f.L.nnz + f.U.nnz
    return row


COLUMNS = ("gradient", "assemble", "matvec", "hvp", "lu")


def report(title, rows):
    print(f"\n{title}")
    print(f"{'N':>6} {'pairs':>9} {'form':>8} {'gradient':>9} {'assemble':>9} {'storage':>9} "
          f"{'peak':>9} {'H @ v':>9} {'H v free':>9} {'LU':>8} {'LU fill':>9} {'|Hv-hv|':>8}")
    for r in rows:
        ms = lambda k, r=r: f"{r[k] * 1e3:>7.1f}ms" if k in r else f"{'-':>9}"
        mb = lambda k, r=r: f"{r[k] / 1e6:>7.1f}MB" if k in r else f"{'-':>9}"
        print(f"{r['N']:>6} {r['P']:>9} {r.get('form', '-'):>8} {ms('gradient')} {ms('assemble')} "
              f"{mb('storage')} {mb('peak')} {ms('matvec')} {ms('hvp')} "
              + (f"{r['lu']:>7.2f}s" if "lu" in r else f"{'-':>8}")
              + (f" {r['fill']:>9}" if "fill" in r else f" {'-':>9}")
              + (f" {r['check']:>8.1e}" if "check" in r else f" {'-':>8}")
              + (f"  ({r['skip']})" if "skip" in r else ""))
    # at fixed l* the neighbours per node grow with N (the node spacing shrinks), so the
    # pairs grow like N^2: fit against N and against the number of pairs P
    for x, label in (("N", "N"), ("P", "pairs P")):
        fits = []
        for k in COLUMNS + ("storage", "peak") + (("P",) if x == "N" else ()):
            pts = [(r[x], r[k]) for r in rows if k in r]
            if len(pts) >= 3:
                xs, vals = np.array(pts, dtype=float).T
                fits.append(f"{'pairs' if k == 'P' else k} "
                            f"{np.polyfit(np.log(xs), np.log(vals), 1)[0]:.2f}")
        print(f"fitted exponents against {label}: " + ", ".join(fits))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="N up to 2000, dense 1000 (smoke run)")
    ap.add_argument("--memory-budget", type=float, default=3.0,
                    help="skip sizes estimated to need more (GB, default 3)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-lu", action="store_true", help="skip the sparse LU column")
    args = ap.parse_args()
    budget = args.memory_budget * 1e9
    Ns = [1000, 2000] if args.quick else [1000, 2000, 4800, 10_000]
    for l_star in (0.01, 0.1):
        sc = CHAScenario(l_star=l_star)
        rows = [measure(sc, N, "neighbours", budget, args.repeat, not args.no_lu) for N in Ns]
        report(f"FiniteDifference, neighbour list, l* = {l_star} (A0 = {sc.A0}, a = {sc.a})",
               rows)
    sc = CHAScenario(l_star=0.5)
    rows = [measure(sc, N, "dense", budget, args.repeat, False)
            for N in ([1000, 1200, 1400] if not args.quick else [1000])]
    report("FiniteDifference, all pairs, l* = 0.5 (dense form)", rows)


if __name__ == "__main__":
    main()
