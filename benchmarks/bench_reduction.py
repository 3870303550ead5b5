"""Cost of the front-position ODE against the DAE faceting flow over the same interval.

For each scenario of ``qsa reproduce fronts`` the DAE (``solve_flow``, BDF2, tol 1e-6,
stopped at the first pair annihilation; run through
:func:`qsa.paper.compare_fronts`) at each resolution N, and the four
reductions (force correction none / newton, fixed length / variable length with
beta = 5) and the four on the manifold of quasi-steady profiles (``profile``,
``profile-lag``, fixed / variable length, numpy only) stopped at their first collision, with the
settings of ``compare_fronts``
(rtol 1e-4, ``method="auto"``: RK45, or Radau for a stiff perimeter mode), each with both
right-hand-side backends (``numpy``, the reference, and the compiled ``numba`` kernel
when numba is installed: ``pip install qsa[fast]``). Prints CPU seconds
(``time.process_time``, best of 5 ODE runs after a warm-up run that also compiles or
loads the numba kernel, robust on a shared machine),
DAE steps / ODE right-hand-side evaluations (with those of the Jacobian), the
speedup against the DAE at each N and the collision times; first, the cost of one
evaluation of the right-hand side alone (``FrontODE.velocity`` at the scenario's splice,
best of many) per backend, fixed and variable length, with and without the Newton
correction. The DAE collision time
converges like N^-2 (second-order differences), so the DAE needs N ~ 2400 to be within
~0.3% of its limit; the ODE has no such cost.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_reduction.py [N ...]``
(default N = 1200 2400).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from qsa.paper import SCENARIOS, compare_fronts
from qsa.reduction import FrontODE

VARIANTS = [(None, False), ("newton", False), (None, True), ("newton", True),
            ("profile", False), ("profile-lag", False), ("profile", True),
            ("profile-lag", True)]


def backends(correction=None):
    """The available right-hand-side backends (numpy only for the profile manifold)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return ["numpy"]
    if correction in ("profile", "profile-lag"):
        return ["numpy"]
    return ["numpy", "numba"]


def ode_cpu(scenario, correction=None, variable=False, backend="numpy", repeat=5):
    """Best-of-``repeat`` CPU time of the ODE alone (to its first collision), n_rhs, ``t_c``."""
    sc = SCENARIOS[scenario]
    eq = sc.splice()
    p = np.array(eq.params["positions"])
    ode = FrontODE(sc.alpha, sc.kstar, eq.params["L"], correction=correction,
                   beta=sc.beta if variable else None, backend=backend)
    opts = {"rtol": 1e-4, "method": "auto"}
    ode.integrate(p, sc.t_final, max_collisions=0, **opts)  # warm-up
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        r = ode.integrate(p, sc.t_final, max_collisions=0, **opts)
        best = min(best, time.process_time() - t0)
    tc = r.first_collision.time if r.events else np.nan
    return best, r.n_rhs, tc


def eval_us(scenario, correction=None, variable=False, backend="numpy", number=200):
    """Best-of-5 wall time of one right-hand-side evaluation (microseconds)."""
    sc = SCENARIOS[scenario]
    eq = sc.splice()
    p, L = np.array(eq.params["positions"]), eq.params["L"]
    cut = tuple(eq.params["cutoff"])
    ode = FrontODE(sc.alpha, sc.kstar, L, correction=correction,
                   beta=sc.beta if variable else None, backend=backend)
    y = np.append(p, L) if variable else p
    ode.rhs(y, cut)  # warm-up (compiles or loads the numba kernel)
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(number):
            ode.rhs(y, cut)
        best = min(best, (time.perf_counter() - t0) / number)
    return 1e6 * best, ode.grid.N


def main(Ns):
    print("one right-hand-side evaluation (us, best of 5 x 200), M quadrature nodes")
    print(f"  {'scenario':12s} {'M':>5s} {'backend':>7s} " + " ".join(
        f"{(c or 'none') + (', var L' if v else ', fixed'):>16s}" for c, v in VARIANTS))
    for name in SCENARIOS:
        for backend in backends():
            cells = [eval_us(name, c, v, backend) if backend in backends(c) else None
                     for c, v in VARIANTS]
            print(f"  {name:12s} {cells[0][1]:5d} {backend:>7s} "
                  + " ".join(f"{c[0]:16.1f}" if c else f"{'-':>16s}" for c in cells))
    for name in SCENARIOS:
        dae = {}
        print(f"{name}: DAE (beta = 5)")
        print(f"  {'N':>5s} {'cpu s':>7s} {'steps':>6s} {'t_c':>9s}")
        for N in Ns:
            c = compare_fronts(name, N=N)
            dae[N] = (c.time_dae, c.collision_dae)
            print(f"  {N:5d} {c.time_dae:7.2f} {c.n_steps_dae:6d} {c.collision_dae:9.5f}")
        head = "".join(f" {'x DAE ' + str(N):>11s}" for N in Ns)
        diff = "".join(f" {'%/' + str(N):>7s}" for N in Ns)
        print(f"  {'reduction':22s} {'backend':>7s} {'cpu s':>7s} {'n_rhs':>5s} {'us/rhs':>7s}"
              f"{head} {'t_c':>10s}{diff}")
        for correction, variable in VARIANTS:
            for backend in backends(correction):
                cpu, n_rhs, tc = ode_cpu(name, correction, variable, backend)
                label = f"{correction or 'none'}, {'variable' if variable else 'fixed'} L"
                sp = "".join(f" {dae[N][0] / cpu:11.0f}" for N in Ns)
                rel = "".join(f" {100 * (tc / dae[N][1] - 1):+7.2f}" for N in Ns)
                print(f"  {label:22s} {backend:>7s} {cpu:7.4f} {n_rhs:5d} {1e6 * cpu / n_rhs:7.0f}"
                      f"{sp} {tc:10.7f}{rel}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1200, 2400])
