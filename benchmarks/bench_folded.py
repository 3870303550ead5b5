"""Cost of the spectrum of a CHA state: Hessian assembly plus the 20 eigenvalues nearest 0.

The energy is Canham-Helfrich + perimeter (``L* = rho L0``) + adhesion with Table T1's
parameters (A0 = 40, a = 1, beta = 60, eps = 0.08, rho = 1.3). The state is a folded
final state read with ``--from FILE`` (a flow result, checkpoint or saved equilibrium,
resampled to each N), or by default the scenario's crenellated start (not an
equilibrium: the timings are those of the same linear algebra, the spectrum is not
physical; it needs N >= 1000 on finite differences). Cases: neighbour lists at Table
T1's l* on finite differences, N = 1200 ... 10^4, and the long-range l* = 0.5 (all
pairs) at N = 1000 ... 1400. Per N: interacting pairs, wall and CPU time of
``spectrum(E, c, k=20, sigma=0)`` (assembly, factorization, Arnoldi) and its peak traced
memory; then the fitted exponent of the wall time against N. A size whose pairs would
need more than 80% of the available memory is skipped with a message.

Each size is measured in two fresh processes: one timed (memory tracing slows numpy's
allocations by ~20%), one with ``tracemalloc`` for the peak; neither sees the other's
cached derivatives. The performance page runs it with one BLAS thread (set
``OPENBLAS_NUM_THREADS=1`` to compare; the dense LAPACK steps of the coarse route use
more threads when given them); wall-clock is noisy on a shared machine, CPU time less so.

With at least ``qsa.energies.adhesion.INTERPOLATE_PAIRS`` pairs the spectrum takes the
panel-interpolated pair Hessian when its coarse rank ``3M`` is below ``N``, and with
``ASSEMBLED_PAIRS_LIMIT`` pairs whatever its rank (``qsa.energies.adhesion_interp``):
the column ``rank`` shows it (``-`` for the assembled blocks), and the memory check then
does not apply. Its shift-invert core is then
eliminated onto the coarse state and the dense ``rank x rank`` system factored by LAPACK
(``qsa.spectra.coarse``).

``--folded`` measures the folded state of f:fold at rho = 1.4 (Table T1, l* = 0.1: the
1200-node flow's state at t = 30 on Fourier(601), kept with the tests) resampled to
each N >= 2400 on finite differences (there it is not exactly an equilibrium; at 1200
nodes the chords of its closest sheets cross); its fold tips
(curvature up to 17) are gentler than the crenellated start's corners (up to 65), so
its compression has the lower rank.

``--gmres`` solves the capacitance by deflated GMRES instead of its LU
(``qsa.spectra.capacitance.ITERATIVE``; the assembled blocks are still needed).

Run: ``python benchmarks/bench_folded.py [--quick] [--N N ...] [--l-star 0.01] [--from FILE]
[--folded] [--gmres]``
"""

from __future__ import annotations

import argparse
import multiprocessing
import time
import tracemalloc
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from qsa import Curve, FiniteDifference, Fourier, io
from qsa.commands._memory import available_bytes, format_bytes
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.energies.adhesion import ASSEMBLED_PAIRS_LIMIT, INTERPOLATE_PAIRS, adhesion_pairs
from qsa.energies.adhesion_interp import coarse_rank
from qsa.paper.scenarios import CHAScenario
from qsa.spectra import capacitance, spectrum

# the folded state of --folded (kept with the tests)
FOLDED = Path(__file__).resolve().parents[1] / "tests" / "reference" / "folded_rho14_601.npz"


def folded_reference():
    """``(curve on Fourier(601), L0)`` of the rho = 1.4 folded state."""
    d = np.load(FOLDED)
    kappa = d["kappa"]
    c = Curve(kappa, np.full(kappa.size, float(d["L"])), Fourier(kappa.size),
              float(d["theta0"]), d["origin"])
    return c, float(d["L0"])


def state(scenario, N, source):
    if source is None:
        x, y = scenario.initial(N)
    elif source == "folded":
        x, y = folded_reference()[0].on_grid(Fourier(2 * N + 1)).positions()
    else:
        loaded = io.load(source)
        c = getattr(loaded, "curve", None)
        x, y = c.positions() if c is not None else (loaded.x, loaded.y)
    return Curve.from_positions(x, y, FiniteDifference(N))


def energy_of(scenario, L0, method):
    return (CanhamHelfrich(scenario.eps) + Perimeter(scenario.beta, scenario.rho * L0)
            + Adhesion(scenario.A0, scenario.l_star, scenario.a, method=method))


# peak memory per interacting pair of the whole measurement (Hessian, implicit-state
# system, its extended-precision copy, capacitance): ~1.2 kB measured at N = 2400, 1.0 kB
# at 4800
BYTES_PER_PAIR = 1.2e3


def _run(l_star, N, method, source, trace, gmres=False):
    """One ``spectrum`` in this (fresh) process: wall and CPU seconds, peak traced bytes."""
    capacitance.ITERATIVE = gmres
    scenario, L0 = scenario_of(l_star, source, N)
    c = state(scenario, N, source)
    E = energy_of(scenario, L0, method)
    if trace:
        tracemalloc.start()
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = spectrum(E, c, k=20, sigma=0.0)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak = tracemalloc.get_traced_memory()[1] if trace else 0
    if trace:
        tracemalloc.stop()
    return {"time": wall, "cpu": cpu, "peak": peak, "n_eig": int(np.size(s.eigenvalues)),
            "nearest0": float(np.min(np.abs(s.eigenvalues)))}


def scenario_of(l_star, source, N):
    """The scenario and reference length ``L0`` of a measurement."""
    if source == "folded":
        return CHAScenario(l_star=l_star, rho=1.4), folded_reference()[1]
    scenario = CHAScenario(l_star=l_star)
    return scenario, Curve.from_positions(*scenario.initial(N), FiniteDifference(N)).length()


def _fresh(*args):
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(_run, *args).result()


def measure(scenario, N, method, source, gmres=False):
    c = state(scenario, N, source)
    E = energy_of(scenario, 1.0, method)
    x, y = c.positions()
    kernel = E.terms()[-1].kernel
    P = adhesion_pairs(kernel, x, y, method=method)[0].size
    rank = None
    if method == "neighbours" and P >= INTERPOLATE_PAIRS:  # the spectrum's own test
        r = coarse_rank(kernel, c)
        rank = r if r < N or P >= ASSEMBLED_PAIRS_LIMIT else None
    need, have = BYTES_PER_PAIR * P, available_bytes()
    if rank is None and need > 0.8 * have:
        print(f"N = {N}: skipped, {P} pairs need about {format_bytes(need)} "
              f"(available {format_bytes(have)})")
        return None
    timed = _fresh(scenario.l_star, N, method, source, False, gmres)
    traced = _fresh(scenario.l_star, N, method, source, True, gmres)
    return {"N": N, "pairs": P, "rank": rank, "time": timed["time"], "cpu": timed["cpu"],
            "peak_MB": traced["peak"] / 1e6, "n_eig": timed["n_eig"],
            "nearest0": timed["nearest0"]}


def report(title, rows):
    rows = [r for r in rows if r is not None]
    print(f"\n{title}")
    print(f"{'N':>7} {'pairs':>10} {'rank':>6} {'time s':>9} {'CPU s':>9} {'peak MB':>9} "
          f"{'eigs':>5} {'min|lam|':>10}")
    for r in rows:
        rank = "-" if r["rank"] is None else str(r["rank"])
        print(f"{r['N']:>7} {r['pairs']:>10} {rank:>6} {r['time']:>9.2f} {r['cpu']:>9.2f} "
              f"{r['peak_MB']:>9.1f} {r['n_eig']:>5} {r['nearest0']:>10.3e}")
    if len(rows) >= 2:
        p = np.polyfit(np.log([r["N"] for r in rows]), np.log([r["time"] for r in rows]), 1)[0]
        print(f"fitted cost exponent (time ~ N^p): p = {p:.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="N up to 2400, dense up to 500")
    ap.add_argument("--l-star", type=float, default=CHAScenario().l_star,
                    help="Table T1's kernel length for the neighbour-list cases")
    ap.add_argument("--from", dest="source", default=None,
                    help="a folded state (flow result, checkpoint or equilibrium file)")
    ap.add_argument("--folded", action="store_true",
                    help="the rho = 1.4 folded state of f:fold instead of the crenellated start")
    ap.add_argument("--N", type=int, nargs="+", default=None,
                    help="the neighbour-list sizes (default 1200 2400 4800 10000)")
    ap.add_argument("--gmres", action="store_true",
                    help="the capacitance by deflated GMRES (capacitance.ITERATIVE)")
    args = ap.parse_args()
    Ns = args.N or ([1200, 2400] if args.quick else [1200, 2400, 4800, 10_000])
    source = "folded" if args.folded else args.source
    if args.folded:  # its sheets touch at 1200 nodes (chords of the resampled curve cross)
        Ns = [N for N in Ns if N >= 2400]
    sc = scenario_of(args.l_star, source, 1200)[0]
    what = "rho = 1.4 folded state" if args.folded else f"rho = {sc.rho}"
    report(f"neighbour list, l* = {sc.l_star} (A0 = {sc.A0}, a = {sc.a}, {what})",
           [measure(sc, N, "neighbours", source, args.gmres) for N in Ns])
    dense = CHAScenario(l_star=0.5)
    report("all pairs, l* = 0.5",
           [measure(dense, N, "dense", args.source) for N in ([1000] if args.quick
                                                              else [1000, 1200, 1400])])


if __name__ == "__main__":
    main()
