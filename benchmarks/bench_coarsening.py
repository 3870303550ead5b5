"""Cost of f:facet's coarsening by the front-position ODE, with the DAE's alongside.

The DAE of :func:`qsa.paper.dae_coarsening` (f:facet's start, ``FacetScenario``) at the
paper's setting (N = 600, backward Euler, tol 1e-4) and resolved (N = 1200, BDF2,
tol 1e-6), to t = 2.2 (after the last event); then the front ODE from the resolved run's
hand-over (:func:`qsa.paper.compare_coarsening`, length free, Newton-corrected force
and uncorrected, rtol 1e-6) through all its collisions to the same time, per
right-hand-side backend (numpy, the reference; numba when installed). Prints CPU seconds
(``time.process_time``; the ODE best of 3 after a warm-up that loads the numba kernel),
evaluations, events and the speed-up over both DAE runs.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_coarsening.py``
"""

from __future__ import annotations

import time

from qsa.paper import compare_coarsening, dae_coarsening
from qsa.reduction import FrontODE
from qsa.reduction.handover import hand_over


def backends():
    try:
        import numba  # noqa: F401
    except ImportError:
        return ["numpy"]
    return ["numpy", "numba"]


def main():
    daes = {}
    for label, kw in (("paper: N=600 BE tol 1e-4", dict(N=600, method="be", tol=1e-4)),
                      ("resolved: N=1200 BDF2 tol 1e-6", dict(N=1200, method="bdf2",
                                                             tol=1e-6))):
        daes[label] = dae_coarsening(t_final=2.2, **kw)
    print(f"{'DAE':34s}{'cpu s':>9s}{'steps':>8s}{'events':>8s}")
    for label, d in daes.items():
        c = compare_coarsening(dae=d)
        n_events = len(c.before_handover) + len(c.dae_events)
        print(f"{label:34s}{d.cpu:9.2f}{d.t.size:8d}{n_events:8d}")
    ref = daes["resolved: N=1200 BDF2 tol 1e-6"]
    base = compare_coarsening(dae=ref)
    i0 = int(next(i for i, t in enumerate(ref.t) if t >= base.handover_time))
    sc = ref.scenario
    L0 = float(ref.length[i0])
    print(f"\nODE from t = {base.handover_time:.4g} ({base.handover_fronts} fronts) to "
          f"t = {ref.t_final:g}")
    print(f"{'correction':>11s}{'backend':>9s}{'cpu s':>9s}{'nfev':>7s}{'events':>8s}"
          f"{'x DAE 600':>11s}{'x DAE 1200':>12s}")
    for corr in (None, "newton"):
        for backend in backends():
            ode = FrontODE(sc.alpha, sc.kstar, L0, beta=sc.beta, L_star=sc.L_star,
                           correction=corr, backend=backend)
            p0 = hand_over(ode, ref.kappa[i0], L0).positions
            ode.integrate(p0, 1e-9, max_collisions=0)
            best, sol = float("inf"), None
            for _ in range(3):
                start = time.process_time()
                sol = ode.integrate(p0, ref.t_final - base.handover_time, rtol=1e-6,
                                    max_collisions=4 * p0.size)
                best = min(best, time.process_time() - start)
            d600 = daes["paper: N=600 BE tol 1e-4"].cpu
            print(f"{str(corr):>11s}{backend:>9s}{best:9.3f}{sol.nfev:7d}{len(sol.events):8d}"
                  f"{d600 / best:11.0f}{ref.cpu / best:12.0f}")


if __name__ == "__main__":
    main()
