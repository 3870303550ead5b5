"""The adhesion pair Hessian by panel interpolation: rank, build, memory and products against N.

For the CHA scenario's crenellated start (Table T1's kernel, ``l* = 0.1``, finite
differences; the folded-like state of ``bench_folded.py``) at N = 1200, 2400, 4800 and
10^4: the panels and coarse points ``M`` of
:func:`~qsa.energies.adhesion_interp.interpolated_pair_hessian` (``B C B^T + D``,
rank ``3M``), the stored entries of ``C``, the build's CPU seconds (panels, ``C``, the
exact diagonal blocks streamed panel by panel, the sampled error check) and its memory
(``nbytes``), the sampled relative row error, the product ``K~ V`` with a block of 20
vectors, and the factored reduced Hessian
(:func:`~qsa.energies.adhesion_interp.interpolated_reduced_hessian`): its assembly and
a product with 20 vectors. Up to N = 2400 the assembled pair Hessian is built too and
the product error ``||K~ V - K V|| / ||K V||`` printed. CPU seconds
(``time.process_time``), products the minimum of 3 repeats, single-threaded BLAS.

Run: ``python benchmarks/bench_pair_interp.py [--N 1200 2400] [--tol 1e-10]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _timing import best_of

from qsa import Curve, FiniteDifference
from qsa.commands._memory import format_bytes
from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
from qsa.energies.adhesion_hessian import adhesion_derivatives
from qsa.energies.adhesion_interp import interpolated_pair_hessian, interpolated_reduced_hessian
from qsa.paper.scenarios import CHAScenario

ASSEMBLED_UP_TO = 2400  # the assembled K needs ~0.8 kB per pair (1.1M pairs at 2400)


def cpu(f, repeat=1):
    """Least CPU seconds of ``repeat`` calls and the result."""
    return best_of(f, repeat, clock=time.process_time)


def run(N, tol):
    sc = CHAScenario(l_star=0.1)
    c = Curve.from_positions(*sc.initial(N), FiniteDifference(N))
    k = AdhesionKernel(sc.A0, sc.l_star, sc.a)
    t_build, H = cpu(lambda: interpolated_pair_hessian(k, c, tol=tol))
    V = np.random.default_rng(0).standard_normal((3 * N, 20))
    t_prod, HV = cpu(lambda: H @ V, 3)
    t_red, R = cpu(lambda: interpolated_reduced_hessian(c, H))
    U = np.random.default_rng(1).standard_normal((2 * N, 20))
    t_rprod, _ = cpu(lambda: R @ U, 3)
    row = [str(N), str(H.n_panels), str(H.M), str(H.rank), f"{H.C.nnz / 1e6:.1f}M",
           f"{t_build:.2f}", format_bytes(H.nbytes), f"{H.error_estimate:.1e}",
           f"{t_prod:.3f}", f"{t_red:.2f}", f"{t_rprod:.3f}"]
    if N <= ASSEMBLED_UP_TO:
        K = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions())).pair_hessian()
        KV = K @ V
        row.append(f"{np.linalg.norm(HV - KV) / np.linalg.norm(KV):.1e}")
    else:
        row.append("-")
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--N", type=int, nargs="+", default=[1200, 2400, 4800, 10_000])
    ap.add_argument("--tol", type=float, default=1e-10)
    args = ap.parse_args(argv)
    print(f"CHA crenellated start, l* = 0.1, tol = {args.tol:g}; CPU seconds; "
          "products with 20 vectors")
    head = ("N", "panels", "M", "rank 3M", "nnz C", "build s", "memory", "estimate",
            "K~ V s", "reduced s", "H U s", "K~ V rel err")
    print(" | ".join(head))
    for N in args.N:
        print(" | ".join(run(N, args.tol)), flush=True)


if __name__ == "__main__":
    main()
