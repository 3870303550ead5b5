"""Hierarchical pair Hessian of the adhesion energy against the assembled sparse one.

For the CHA scenario's crenellated start (Table T1's kernel, ``l* = 0.1``, finite
differences) at N = 1200, 2400, 4800 (``--quick``: the first two; ``--large``: and
10^4): the interacting pairs; the build time of
:func:`~qsa.energies.adhesion_far.hierarchical_pair_hessian` (tree, partition, six
compressed pair functions) and its memory (all, and the near field's part, as stored);
the near pairs per node; the far blocks' median and maximum rank; the product time of
``K V`` for a block of 8 random vectors, hierarchical and assembled (CSR, with its
assembly time and memory); and the relative product error against the assembled
matrix with the built-in estimate. Both forms' memory is estimated first (about
0.8 kB per pair for the assembled one, 100 kB per node for the hierarchical one) and a
form is skipped above 8 GB, or above the memory available, with a message. Times are
CPU seconds (``time.process_time``), the minimum of 3 product repeats, single-threaded
BLAS.

Run: ``python benchmarks/bench_far_field.py [--quick | --large] [--tol 1e-10]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _timing import best_of

from qsa import Curve, FiniteDifference
from qsa.commands._memory import available_bytes, format_bytes
from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
from qsa.energies.adhesion_far import hierarchical_pair_hessian
from qsa.energies.adhesion_hessian import adhesion_derivatives
from qsa.paper.scenarios import CHAScenario

BYTES_PER_PAIR = 0.8e3
LIMIT = 8e9
# generous bound of the hierarchical form's build (27 kB per node measured at N = 10^4)
H_BYTES_PER_NODE = 100e3


def cpu(f, repeat=1):
    """Least CPU seconds of ``repeat`` calls and the result."""
    return best_of(f, repeat, clock=time.process_time)


def estimated_pairs(N):
    """Pairs of the crenellated start, ~N^2 (271k at N = 1200)."""
    return 271e3 * (N / 1200) ** 2


def run(N, tol, leaf):
    sc = CHAScenario()
    c = Curve.from_positions(*sc.initial(N), FiniteDifference(N))
    k = AdhesionKernel(sc.A0, sc.l_star, sc.a)
    x, y = c.positions()
    row = {"N": N}
    row["t_build"], H = cpu(lambda: hierarchical_pair_hessian(k, x, y, c.dsigma, tol=tol,
                                                              leaf_size=leaf))
    row["mem_h"] = H.nbytes
    row["mem_near"] = sum(g.near.data.nbytes + g.near.indices.nbytes + g.near.indptr.nbytes
                          for g in H.G.values())
    ranks = np.concatenate([g.ranks for g in H.G.values()])
    row["rank"] = (float(np.median(ranks)), int(ranks.max()) if ranks.size else 0)
    row["fallback"] = sum(g.n_fallback for g in H.G.values())
    row["near_per_node"] = 2 * H.near_nnz / N
    row["est"] = max(H.error_estimates.values())
    V = np.random.default_rng(0).standard_normal((3 * N, 8))
    row["t_h"], HV = cpu(lambda: H @ V, 3)
    need = BYTES_PER_PAIR * estimated_pairs(N)
    if need > min(LIMIT, 0.8 * available_bytes()):
        print(f"N = {N}: assembled matrix skipped (estimated {format_bytes(need)})")
        row.update(pairs=np.nan, t_asm=np.nan, mem_k=np.nan, t_k=np.nan, err=np.nan)
        return row
    t_asm, K = cpu(lambda: adhesion_derivatives(
        k, c, adhesion_pairs(k, x, y)).pair_hessian())
    row["pairs"] = (K.nnz - 9 * N) / 18
    row["t_asm"] = t_asm
    row["mem_k"] = K.data.nbytes + K.indices.nbytes + K.indptr.nbytes
    row["t_k"], KV = cpu(lambda: K @ V, 3)
    row["err"] = float(np.linalg.norm(HV - KV) / np.linalg.norm(KV))
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--large", action="store_true", help="add N = 10^4")
    ap.add_argument("--quick", action="store_true", help="N = 1200 and 2400 only")
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--leaf", type=int, default=64)
    args = ap.parse_args(argv)
    sizes = [1200, 2400] + ([] if args.quick else [4800]) + ([10_000] if args.large else [])
    print(f"tol = {args.tol:g}, leaf size {args.leaf}; CPU seconds; product: 8 vectors")
    head = ("N", "pairs", "build s", "H mem (near)", "near/node", "rank med/max", "H KV s",
            "asm s", "K mem", "K KV s", "rel err", "estimate")
    print(" | ".join(head))
    for N in sizes:
        need = N * H_BYTES_PER_NODE
        if need > min(LIMIT, 0.8 * available_bytes()):
            print(f"N = {N} skipped: the hierarchical form may need {format_bytes(need)}")
            continue
        r = run(N, args.tol, args.leaf)
        fmt = lambda v: format_bytes(v) if np.isfinite(v) else "-"
        print(" | ".join([
            str(N), f"{r['pairs']:.3g}", f"{r['t_build']:.2f}",
            f"{fmt(r['mem_h'])} ({fmt(r['mem_near'])})",
            f"{r['near_per_node']:.0f}", f"{r['rank'][0]:.0f}/{r['rank'][1]}",
            f"{r['t_h']:.3f}", f"{r['t_asm']:.2f}", fmt(r["mem_k"]), f"{r['t_k']:.3f}",
            f"{r['err']:.1e}", f"{r['est']:.1e}"]) + (f"  ({r['fallback']} SVD fallbacks)"
                                                     if r["fallback"] else ""))


if __name__ == "__main__":
    main()
