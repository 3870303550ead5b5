"""Per-solve cost of the shift-invert capacitance by GMRES with the compressed pair Hessian.

The state is the CHA scenario's crenellated start (Table T1, ``l* = 0.1``; not an
equilibrium: the linear algebra of ``spectrum(E, c, k=20, sigma=0)``'s shift-invert
system at ``sigma = 0``, not a physical spectrum), energy Canham-Helfrich + perimeter +
adhesion. Per N:

* ``hmat``: CPU seconds and bytes of
  :func:`~qsa.energies.adhesion_far.hierarchical_pair_hessian` (``tol``);
* ``gmres``: :class:`~qsa.spectra.capacitance_iterative.IterativeCapacitanceCore` on
  :meth:`~qsa.energies.adhesion_hessian.AdhesionDerivatives.operator_reduced_hessian`
  (nothing of size ``N^2`` or ``pairs``): setup CPU (with the deflation's Arnoldi run,
  ``--deflate`` Ritz vectors from ``--arnoldi`` steps), then per solve of one right-hand
  side (``phi`` rows, as in Arnoldi) its CPU seconds and GMRES iterations;
* with ``--compare`` (N <= 4800): the LU capacitance on the assembled Hessian (setup and
  per-solve CPU) and the relative difference of the two solutions' ``phi``.

At N beyond the comparison the local blocks are those of Canham-Helfrich + perimeter
alone (the assembled Lagrangian Hessian is what does not fit); the costs are those
of the same systems. CPU time (``time.process_time``), single-threaded BLAS.

Run: ``python benchmarks/bench_capacitance_gmres.py [--N 2400 4800 10000] [--compare]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp

from qsa import Curve, FiniteDifference
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.energies.adhesion import adhesion_pairs
from qsa.energies.adhesion_far import hierarchical_pair_hessian
from qsa.energies.adhesion_hessian import adhesion_derivatives
from qsa.paper.scenarios import CHAScenario
from qsa.spectra import FactoredNormalOperator, lagrange_hessian
from qsa.spectra.capacitance import CapacitanceCore
from qsa.spectra.capacitance_iterative import IterativeCapacitanceCore
from qsa.spectra.factored import local_blocks


def _operator(E, c):
    LH = lagrange_hessian(E, c, closure="curvature")
    return FactoredNormalOperator.from_lagrangian(c, LH.matrix)


def _solves(core, B):
    out, cpu = [], []
    for j in range(B.shape[1]):
        t = time.process_time()
        out.append(core.solve(B[:, j]))
        cpu.append(time.process_time() - t)
    return np.column_stack(out), cpu


def measure(N, tol, compare, deflate, arnoldi, n_solves=3):
    sc = CHAScenario()
    c = Curve.from_positions(*sc.initial(N), FiniteDifference(N))
    L0 = c.length()
    ad = Adhesion(sc.A0, sc.l_star, sc.a)
    kernel = ad.kernel
    row = {"N": N}
    t = time.process_time()
    H = hierarchical_pair_hessian(kernel, *c.positions(), c.dsigma, tol=tol)
    row["hmat_cpu"], row["hmat_MB"] = time.process_time() - t, H.nbytes / 2**20
    row["hmat_err"] = max(H.error_estimates.values())
    t = time.process_time()
    pairs = adhesion_pairs(kernel, *c.positions())
    row["pairs"] = int(pairs[0].size)
    d = adhesion_derivatives(kernel, c, pairs)
    del pairs
    K = d.operator_reduced_hessian(H)  # holds the local parts only
    row["local_cpu"] = time.process_time() - t
    local = CanhamHelfrich(sc.eps) + Perimeter(sc.beta, sc.rho * L0)
    op = _operator(local + ad, c) if compare else _operator(local, c)
    w2 = np.concatenate([c.dsigma, c.dsigma])
    K = K.with_left(sp.diags(w2) @ K.left)
    blocks, dgk = local_blocks(op, 0.0), sp.diags(op.gk)
    t = time.process_time()
    it = IterativeCapacitanceCore(blocks, K, dgk, N, deflate=deflate, arnoldi=arnoldi)
    row["gmres_setup"] = time.process_time() - t
    B = np.zeros((it.shape[0], n_solves))
    B[:N] = c.dsigma[:, None] * np.random.default_rng(0).standard_normal((N, n_solves))
    X, cpu = _solves(it, B)
    row["gmres_solve"], row["iters"] = float(np.min(cpu)), it.iterations
    if compare:
        del d
        t = time.process_time()
        lu = CapacitanceCore(blocks, op.reduced, dgk, N)
        row["lu_setup"] = time.process_time() - t
        Y, cpu = _solves(lu, B)
        row["lu_solve"] = float(np.min(cpu))
        row["phi_diff"] = float(np.linalg.norm(X[:N] - Y[:N]) / np.linalg.norm(Y[:N]))
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, nargs="+", default=[2400, 4800, 10_000])
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--deflate", type=int, default=200, help="Ritz vectors deflated")
    ap.add_argument("--arnoldi", type=int, default=300, help="Arnoldi steps for them")
    ap.add_argument("--compare", action="store_true",
                    help="also the LU capacitance on the assembled Hessian (N <= 4800)")
    args = ap.parse_args()
    print(f"{'N':>6} {'pairs':>10} {'hmat s':>7} {'hmat MiB':>9} {'err':>8} {'local s':>8} "
          f"{'setup s':>8} {'solve s':>8} {'iters':>12} {'LU setup':>9} {'LU solve':>9} "
          f"{'phi diff':>9}")
    for N in args.N:
        r = measure(N, args.tol, args.compare and N <= 4800, args.deflate, args.arnoldi)
        lu = (f"{r['lu_setup']:>9.2f} {r['lu_solve']:>9.3f} {r['phi_diff']:>9.1e}"
              if "lu_setup" in r else f"{'-':>9} {'-':>9} {'-':>9}")
        print(f"{N:>6} {r['pairs']:>10} {r['hmat_cpu']:>7.2f} {r['hmat_MB']:>9.1f} "
              f"{r['hmat_err']:>8.1e} {r['local_cpu']:>8.2f} {r['gmres_setup']:>8.2f} "
              f"{r['gmres_solve']:>8.3f} {str(r['iters']):>12} {lu}", flush=True)


if __name__ == "__main__":
    main()
