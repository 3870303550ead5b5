"""Linear algebra shared by the operator layers: structured matrices and LU factorizations.

* :mod:`qsa.linalg.structured` -- ``SparsePlusLowRank`` (``S + U V^T``: the sparse
  finite-difference Hessians with the perimeter penalty's rank-one term kept factored,
  O(N) memory and products) and ``ReducedHessian`` (the Hessian of an energy whose
  state is defined implicitly by sparse equations: dense as a matrix, O(nnz) in
  factored form), with ``to_dense`` and ``is_matrix_like``.
* :mod:`qsa.linalg.hierarchical` -- matrices of pair functions of points as an exact
  near field plus low-rank far blocks (cluster tree, adaptive cross approximation
  with an a posteriori error estimate): O(N log N) storage for smooth kernels.
* :mod:`qsa.linalg.lu` -- :func:`factorize` (dense LAPACK, sparse SuperLU, or either
  with a thin border; ``det_sign``) and :class:`LowRankUpdate` (Woodbury): the one LU
  of the package.
"""

from qsa.linalg.lu import Factorization, LowRankUpdate, factorize, permutation_parity
from qsa.linalg.structured import (
    BlockSparse,
    ReducedHessian,
    SparsePlusLowRank,
    is_matrix_like,
    to_dense,
)

__all__ = ["SparsePlusLowRank", "ReducedHessian", "BlockSparse", "to_dense", "is_matrix_like",
           "factorize", "Factorization", "LowRankUpdate", "permutation_parity"]
