"""ReducedHessian: the factored form equals the dense reduced Hessian under every operation."""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa.linalg import ReducedHessian, SparsePlusLowRank, to_dense


def random_reduced(seed, p=7, m=5, low_rank=0):
    """A random instance and its dense value, formed independently of the class."""
    rng = np.random.default_rng(seed)
    sym = lambda A: A + A.T
    Luu = sym(rng.standard_normal((p, p)))
    Lyu = rng.standard_normal((m, p))
    Lyy = sym(rng.standard_normal((m, m)))
    cY = np.tril(rng.standard_normal((m, m))) + 3 * np.eye(m)
    cU = rng.standard_normal((m, p))
    left = np.diag(rng.uniform(0.5, 2, p))
    S = sp.random(p, p, density=0.3, random_state=seed).toarray()
    U, V = rng.standard_normal((p, low_rank)), rng.standard_normal((p, low_rank))
    Z = -np.linalg.solve(cY, cU)
    K = Luu + Lyu.T @ Z + Z.T @ Lyu + Z.T @ Lyy @ Z
    dense = S + left @ K + U @ V.T
    H = ReducedHessian(*(sp.csr_matrix(A) for A in (Luu, Lyu, Lyy, cY, cU)),
                       left=sp.csr_matrix(left), S=sp.csr_matrix(S), U=U, V=V)
    return H, dense


def test_products_transpose_and_dense():
    H, D = random_reduced(0, low_rank=2)
    x = np.arange(7.0)
    X = np.random.default_rng(1).standard_normal((7, 3))
    assert np.allclose(H @ x, D @ x)
    assert np.allclose(H @ X, D @ X)
    assert np.allclose(X.T @ H, X.T @ D)
    assert np.allclose(H.T.toarray(), D.T)
    assert np.allclose(H.toarray(block=2), D)
    assert np.allclose(H.aslinearoperator() @ x, D @ x)
    assert np.allclose(to_dense(H), D)


def test_algebra_stays_factored():
    H, D = random_reduced(2)
    H2, D2 = random_reduced(3, low_rank=1)
    S = sp.random(7, 7, density=0.4, random_state=4, format="csr")
    L = SparsePlusLowRank(S, np.ones(7), np.arange(7.0))
    cases = {
        "sum": (H + H2, D + D2),
        "sparse": (H + S, D + S.toarray()),
        "rsparse": (S + H, D + S.toarray()),
        "lowrank": (H + L, D + L.toarray()),
        "rlowrank": (L + H, D + L.toarray()),
        "scaled": (-2.5 * H - S, -2.5 * D - S.toarray()),
        "left": (S @ H, S.toarray() @ D),
        "right": (H @ S, D @ S.toarray()),
        "lowrank-right": (H @ L, D @ L.toarray()),
        "lowrank-left": (L @ H, L.toarray() @ D),
    }
    for name, (A, ref) in cases.items():
        assert isinstance(A, ReducedHessian), name
        assert np.allclose(A.toarray(), ref), name
    dense_sum = H + np.eye(7)
    assert isinstance(dense_sum, np.ndarray) and np.allclose(dense_sum, D + np.eye(7))


def test_sum_on_the_same_scaling_stacks_the_states():
    """Equal left and right factors: one core with both states, still the compact system."""
    H, D = random_reduced(8, low_rank=1)
    H2, D2 = random_reduced(9, m=4)
    H2 = ReducedHessian(H2.Luu, H2.Lyu, H2.Lyy, H2.cY, H2.cU, left=H.left, S=H2.S)
    D2 = H2.toarray()
    total = H + H2
    assert total.left.shape == (7, 7) and total.cY.shape == (9, 9)
    assert np.allclose(total.toarray(), D + D2)
    assert total.augmented(0.0).shape[0] == 7 + 2 * 9
    b = np.linspace(-1, 1, 7)
    assert np.allclose((D + D2 - 0.2 * np.eye(7)) @ (total.shift_invert(0.2) @ b), b)


@pytest.mark.parametrize("low_rank", [0, 2])
def test_shift_invert(low_rank):
    H, D = random_reduced(5, low_rank=low_rank)
    B = sp.diags(np.linspace(1, 2, 7))
    b = np.linspace(-1, 1, 7)
    for sigma, mass in ((0.3, None), (-1.0, B)):
        Bd = np.eye(7) if mass is None else B.toarray()
        x = H.shift_invert(sigma, mass) @ b
        assert np.allclose((D - sigma * Bd) @ x, b)
    assert H.augmented(0.0).shape[0] == 7 + 2 * 5  # diagonal scalings: the compact system
    # general left factor: the five-block system
    G = sp.random(7, 7, density=0.5, random_state=7, format="csr") + 2 * sp.identity(7)
    HG, DG = G @ H, G.toarray() @ D
    assert HG.augmented(0.0).shape[0] == 7 + 2 * 7 + 2 * 5
    x = HG.shift_invert(0.3) @ b
    assert np.allclose((DG - 0.3 * np.eye(7)) @ x, b)


def test_bad_input():
    H, _ = random_reduced(6)
    with pytest.raises(ValueError, match="shape"):
        ReducedHessian(H.Luu, H.Lyu, H.Lyy, H.cY, H.cU, S=sp.identity(3))
    with pytest.raises(ValueError, match="Luu"):
        ReducedHessian(H.Luu, H.Lyu.T, H.Lyy, H.cY, H.cU)
    with pytest.raises(ValueError, match="singular"):
        zero = sp.csr_matrix((7, 7))
        Hs = ReducedHessian(zero, sp.csr_matrix((5, 7)), sp.csr_matrix((5, 5)), H.cY, H.cU)
        Hs.shift_invert(0.0)  # H = 0
