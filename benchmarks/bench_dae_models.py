"""Cost of one residual + one Newton-matrix assembly of the DAE models against N.

Prints a table per model and the exponent p of a least-squares fit
``time ~ N^p`` (targets: p <= 1.15 for faceting and for the second-order flow of
``FunctionalizedCurvature``, p <= 1.3 for CHA with the neighbour list).

For CHA the kernel width is tied to the grid (``l* = 2 L/N``), so every node
has the same number of neighbours: this measures the algorithm, not a change of
physics. A second CHA table keeps the paper's folding kernel fixed
(``l* = 0.01``, Table T1 read literally) over the resolved range: there the neighbours per
node grow like N until the kernel is resolved by many nodes, and the cost with
them. The last table is the paper's long-range kernel (``l* = 1/2``), whose
adhesion block is dense. A last table times whole short flows (``solve_flow``, BDF2)
of the faceting energy by ``FacetingFlow`` and by the generic ``SecondOrderFlow``, and of
``FunctionalizedCurvature`` (sixth order), per accepted step.

Run: ``python benchmarks/bench_dae_models.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from qsa.energies import Faceting, FunctionalizedCurvature, Perimeter
from qsa.flows import solve_flow
from qsa.flows.dae import FacetingFlow, SecondOrderFlow, equalize_chords
from qsa.paper import CONVERGENCE, CHAScenario
from qsa.resample import resample_closed


def wobbly(N, folds=13, depth=0.08):
    th = 2 * np.pi * np.arange(4096) / 4096
    r = 1 + depth * np.cos(folds * th) + 0.03 * np.sin(2 * th)
    # equal arc length, then the models' own projection to equal chords (setup does it)
    x, y, _ = resample_closed(1.2 * r * np.cos(th), 1.2 * r * np.sin(th), N)
    x, y, L = equalize_chords(x, y)
    return x, y, L


def time_assembly(sys, repeats):
    rng = np.random.default_rng(0)
    y = sys.y0 * (1 + 1e-6 * rng.standard_normal(sys.size))
    ydot = 1e-3 * rng.standard_normal(sys.size)
    best = np.inf
    for _ in range(repeats):
        # CPU time of this process: steadier than wall time on a shared machine
        # (the kernels are single-threaded NumPy/SciPy)
        t0 = time.process_time()
        sys.residual(y, ydot)
        J = sys.jacobian(y, ydot, 1e3)
        best = min(best, time.process_time() - t0)
    return best, J.nnz


def run(title, Ns, make_model, repeats, target=None):
    print(f"\n{title}")
    print(f"{'N':>8} {'unknowns':>9} {'nnz(J)':>10} {'nnz/N':>7} {'cpu [ms]':>10} {'us/node':>8}")
    times = []
    for N in Ns:
        x, y, L = wobbly(N)
        sys = make_model(N, L).setup(x, y)
        t, nnz = time_assembly(sys, repeats)
        times.append(t)
        print(f"{N:>8} {sys.size:>9} {nnz:>10} {nnz / N:>7.1f} {1e3 * t:>10.2f} "
              f"{1e6 * t / N:>8.2f}")
    p = np.polyfit(np.log(Ns), np.log(times), 1)[0]
    verdict = ""
    if target is not None:
        verdict = f"  (target <= {target:.2f}: {'ok' if p <= target else 'MISSED'})"
    print(f"fitted exponent p = {p:.3f}{verdict}")
    if len(Ns) >= 5:  # small N is dominated by fixed per-call overhead
        q = np.polyfit(np.log(Ns[-3:]), np.log(times[-3:]), 1)[0]
        print(f"exponent over the three largest N: {q:.3f}")
    return p


def newton_solve_table(Ns, steps=(1e-4, 1e-3, 1e-2)):
    """One Newton solve with the long-range kernel: full sparse LU vs local LU + GMRES."""
    import scipy.sparse.linalg as spla

    print("\nCHA l* = 1/2: one Newton-matrix solve, full sparse LU vs LU(J_local) + GMRES")
    print(f"{'N':>6} {'k':>8} {'LU(J) [ms]':>11} {'LU(J_loc)+GMRES [ms]':>21} {'its':>4} "
          f"{'ratio':>6}")
    model = CONVERGENCE.model()
    for N in Ns:
        x, y, _ = wobbly(N)
        sys = model.setup(x, y)
        b = np.random.default_rng(0).standard_normal(sys.size)
        for k in steps:
            J = sys.jacobian(sys.y0, np.zeros(sys.size), 1 / k)
            Jl, _ = sys.jacobian_parts(sys.y0, np.zeros(sys.size), 1 / k)
            t0 = time.process_time()
            spla.splu(J).solve(b)
            t_full = time.process_time() - t0
            t0 = time.process_time()
            lu = spla.splu(Jl)
            its = []
            spla.gmres(J, b, M=spla.LinearOperator(J.shape, lu.solve), rtol=1e-12, restart=80,
                       maxiter=10, callback=its.append, callback_type="pr_norm")
            t_gm = time.process_time() - t0
            print(f"{N:>6} {k:>8.0e} {1e3 * t_full:>11.2f} {1e3 * t_gm:>21.2f} {len(its):>4} "
                  f"{t_full / t_gm:>6.1f}")


def flow_table(Ns, T=2e-3, tol=1e-5):
    """Whole BDF2 flows from a perturbed circle: steps, Newton iterations, CPU per step."""
    models = {
        "FacetingFlow": lambda: FacetingFlow(alpha=0.1, kstar=5.0, beta=5.0, L_star=8.0),
        "SecondOrderFlow(Faceting)": lambda: SecondOrderFlow(Faceting(0.1, 5.0)
                                                             + Perimeter(5.0, 8.0)),
        "SecondOrderFlow(FC)": lambda: SecondOrderFlow(FunctionalizedCurvature(0.1, 1.0, 5.0)
                                                       + Perimeter(5.0, 8.0)),
    }
    print(f"\nsolve_flow, BDF2, t = {T:g}, tol = {tol:g}, r = 1.2 (1 + 0.05 cos 5t)")
    print(f"{'model':>26} {'N':>6} {'steps':>6} {'newton':>7} {'LU':>5} {'cpu [s]':>8} "
          f"{'ms/step':>8}")
    th = 2 * np.pi * np.arange(4096) / 4096
    r = 1.2 * (1 + 0.05 * np.cos(5 * th))
    for name, make in models.items():
        for N in Ns:
            t0 = time.process_time()
            res = solve_flow(make(), (r * np.cos(th), r * np.sin(th)), T, N=N, tol=tol,
                             method="bdf2", progress=False)
            cpu = time.process_time() - t0
            print(f"{name:>26} {N:>6} {res.n_steps:>6} {res.n_newton:>7} "
                  f"{res.n_factorizations:>5} {cpu:>8.2f} {1e3 * cpu / res.n_steps:>8.2f}"
                  + ("" if res.success else f"  ({res.message})"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sweeps")
    args = ap.parse_args(argv)
    rep = 3 if args.quick else 5
    facet_N = [100, 300, 1000, 3000, 10000] + ([] if args.quick else [30000, 100000])
    cha_N = [100, 300, 1000, 3000] + ([] if args.quick else [10000])
    run("FacetingFlow(alpha=0.1, kstar=5, beta=5, L_star=8)", facet_N,
        lambda N, L: FacetingFlow(alpha=0.1, kstar=5.0, beta=5.0, L_star=8.0), rep, 1.15)
    run("SecondOrderFlow(FunctionalizedCurvature(0.1, 1, 5) + Perimeter(5, 8))", facet_N,
        lambda N, L: SecondOrderFlow(FunctionalizedCurvature(0.1, 1.0, 5.0)
                                     + Perimeter(5.0, 8.0)), rep, 1.15)
    run("CHA, neighbour list, l* = 2 L/N (fixed neighbours per node)", cha_N,
        lambda N, L: replace(CHAScenario(), l_star=2 * L / N).model(),
        rep, 1.3)
    fixed_N = [1000, 2000, 4000] if args.quick else [1000, 2000, 4000, 8000]
    run("CHA, neighbour list, l* = 0.01 (Table T1 read literally)", fixed_N,
        lambda N, L: CHAScenario.literal().model(), rep)
    run("CHA, paper's convergence-study kernel l* = 1/2 (dense adhesion block)",
        [100, 200, 400, 800],
        lambda N, L: CONVERGENCE.model(), rep)
    newton_solve_table([100, 400] if args.quick else [100, 200, 400, 800])
    flow_table([100, 200] if args.quick else [100, 200, 400])


if __name__ == "__main__":
    main()
