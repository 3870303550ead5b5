"""Cost of the front-position ODE against the DAE faceting flow over the same interval.

For each scenario of ``qsa reproduce fronts`` and each DAE resolution N, runs
:func:`qsa.reduction.compare.compare_fronts` (DAE: ``solve_flow``, BDF2, tol 1e-6,
stopped at the first pair annihilation; ODE: RK45, rtol 1e-4, stopped at its first
collision) and prints CPU seconds (``time.process_time``, robust on a shared
machine), steps / right-hand-side evaluations, the speedup, and the collision times.
The DAE collision time converges like N^-2 (second-order differences), so the
DAE needs N ~ 2400 to be within ~0.3% of its limit; the ODE has no such cost.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_reduction.py [N ...]``
(default N = 1200 2400).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from qsa.reduction.compare import SCENARIOS, compare_fronts, scenario_splice
from qsa.reduction.ode import FrontODE


def ode_cpu(scenario, repeat=5):
    """Best-of-``repeat`` CPU time of the ODE alone (first collision), and its nfev."""
    eq = scenario_splice(scenario)
    p = np.array(eq.params["positions"])
    ode = FrontODE(0.1, 5.0, eq.params["L"])
    best, nfev = np.inf, 0
    for _ in range(repeat):
        t0 = time.process_time()
        r = ode.integrate(p, SCENARIOS[scenario].t_final, rtol=1e-4, max_collisions=0)
        best = min(best, time.process_time() - t0)
        nfev = r.nfev
    return best, nfev


def main(Ns):
    print(f"{'scenario':12s} {'N':>5s} {'DAE cpu s':>10s} {'steps':>6s} {'ODE cpu s':>10s} "
          f"{'nfev':>5s} {'speedup':>8s} {'t_c DAE':>9s} {'t_c ODE':>9s} {'diff %':>7s}")
    for name in SCENARIOS:
        t_ode, nfev = ode_cpu(name)
        for N in Ns:
            s = compare_fronts(name, N=N).summary
            print(f"{name:12s} {N:5d} {s['time_dae']:10.2f} {s['n_steps_dae']:6d} "
                  f"{t_ode:10.3f} {nfev:5d} {s['time_dae'] / t_ode:8.0f} "
                  f"{s['collision_dae']:9.5f} {s['collision_ode']:9.5f} "
                  f"{100 * s['collision_rel_diff']:7.2f}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1200, 2400])
