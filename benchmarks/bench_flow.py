"""Cost of ``solve_flow``: the paper's CHA example, cost per step against N, and the ratio
against the dense reference algorithm (dense Jacobian + dense LU + full Newton, as in the
code behind the paper).

Targets: the appendix example (N = 100, tol 1e-4, physical t = 0.2) in <= 1.5 s
and N = 400 in <= 15 s; fitted exponent of the cost per step <= 1.15 for faceting
(N = 1e2 .. 1e5) and <= 1.3 for CHA with the neighbour list (N = 1e2 .. 1e4).

Times are CPU seconds of this process (``time.process_time``; the kernels run on one
thread with OPENBLAS_NUM_THREADS=1), steadier than wall time on a shared machine; wall
time is printed too.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_flow.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from qsa.flows import FacetingFlow, solve_flow
from qsa.paper import CONVERGENCE, CHAScenario


def timed(fn, *args, **kwargs):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.process_time() - c0, time.perf_counter() - w0


def paper_example(Ns, targets):
    print("\nThe appendix example: CHA (l* = 1/2), tol 1e-4, backward Euler with step "
          "doubling, physical t = 0.2")
    print(f"{'N':>5} {'steps':>6} {'newton':>7} {'LU':>5} {'cpu [s]':>8} {'wall [s]':>9} "
          f"{'target':>7}")
    sc = CONVERGENCE
    init = sc.samples()
    for N in Ns:
        res, cpu, wall = timed(solve_flow, sc.model(), init, sc.t_final, N=N, tol=sc.tol,
                               t_eval=[sc.t_final], progress=False)
        target = targets.get(N)
        verdict = "" if target is None else ("ok" if cpu <= target else "MISSED")
        print(f"{N:>5} {res.n_steps:>6} {res.n_newton:>7} {res.n_lu:>5} "
              f"{cpu:>8.2f} {wall:>9.2f} {target if target else '':>7} {verdict}")


def wobbly(M=8192, lobes=9, depth=0.06):
    th = 2 * np.pi * np.arange(M) / M
    r = 1.2 * (1 + depth * np.cos(lobes * th) + 0.02 * np.sin(2 * th))
    return r * np.cos(th), r * np.sin(th)


def cost_per_step(title, Ns, make_model, first_step, steps=4, target=None):
    """CPU seconds per accepted step (after the first), same initial shape at every N."""
    print(f"\n{title}")
    print(f"{'N':>7} {'unknowns':>9} {'steps':>6} {'newton/step':>11} {'LU/step':>8} "
          f"{'cpu/step [s]':>13} {'us/node':>8}")
    init = wobbly()
    costs = []
    for N in Ns:
        stamps = []
        res = solve_flow(make_model(N), init, 1.0, N=N, tol=1e3, first_step=first_step,
                         max_step=first_step, max_steps=steps + 1, progress=False,
                         t_eval=[1.0], callback=lambda t, y, s, stamps=stamps: stamps.append(
                             time.process_time()) and False)
        per = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
        costs.append(per)
        print(f"{N:>7} {res.system.size:>9} {res.n_steps:>6} "
              f"{res.n_newton / res.n_steps:>11.1f} {res.n_lu / res.n_steps:>8.2f} "
              f"{per:>13.4f} {1e6 * per / N:>8.2f}")
    p = np.polyfit(np.log(Ns), np.log(costs), 1)[0]
    verdict = "" if target is None else (
        f"  (target <= {target}: {'ok' if p <= target else 'MISSED'})")
    print(f"fitted exponent p = {p:.3f}{verdict}")
    return p


def dense_reference_ratio(Ns, passes):
    """Same problem, same (fixed) steps: qsa's solver against dense Jacobian + dense LU."""
    print("\nSame steps (fixed k = 1e-4 passes from the appendix start): qsa (simplified Newton, "
          "Woodbury/sparse LU)\nagainst the paper's algorithm (full Newton, dense Jacobian, "
          "dense LU)")
    print(f"{'N':>5} {'passes':>6} {'qsa cpu/pass':>13} {'dense cpu/pass':>15} {'ratio':>7} "
          f"{'max |dX|':>9}")
    init = CONVERGENCE.samples()
    h = 2e-4
    for N in Ns:
        n = passes.get(N, 3)
        T = n * h
        kw = dict(N=N, tol=1e3, first_step=h, max_step=h, t_eval=[T], progress=False,
                  newton_tol=1e-9)
        ours, c1, _ = timed(solve_flow, CONVERGENCE.model(), init, T, **kw)
        ref, c2, _ = timed(solve_flow, CONVERGENCE.model(), init, T, linear_solver="dense",
                           reuse_factorizations=False, **kw)
        dx = np.max(np.abs(ours.states[-1][: 2 * N] - ref.states[-1][: 2 * N]))
        print(f"{N:>5} {ours.n_steps:>6} {c1 / n:>13.4f} {c2 / n:>15.4f} {c2 / c1:>7.1f} "
              f"{dx:>9.1e}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sweeps")
    args = ap.parse_args(argv)
    paper_example([100] if args.quick else [100, 400], {100: 1.5, 400: 15.0})
    facet_N = [100, 1000, 10000] if args.quick else [100, 300, 1000, 3000, 10000, 30000, 100000]
    cost_per_step("FacetingFlow(alpha=0.1, kstar=5, beta=5, L*=9): cost per step", facet_N,
                  lambda N: FacetingFlow(alpha=0.1, kstar=5.0, beta=5.0, L_star=9.0), 1e-7,
                  target=1.15)
    cha_N = [100, 1000] if args.quick else [100, 300, 1000, 3000, 10000]
    cost_per_step("CHA, neighbour list, l* = 2 L/N (fixed neighbours per node): cost per step",
                  cha_N, lambda N: replace(CHAScenario(), l_star=2 * 7.6 / N).model(), 1e-7,
                  target=1.3)
    dense_reference_ratio([100, 200] if args.quick else [100, 200, 400, 800],
                          {100: 5, 200: 4, 400: 3, 800: 2})


if __name__ == "__main__":
    main()
