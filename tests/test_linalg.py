"""ReducedHessian: the factored form equals the dense reduced Hessian under every operation."""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa.linalg import (
    BlockSparse,
    LowRankUpdate,
    ReducedHessian,
    SparsePlusLowRank,
    factorize,
    permutation_parity,
    to_dense,
)


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


def test_transposes_and_factors_are_shared_only_with_the_same_core():
    """Matrices made from one another share what is derived from the core, never a stale one."""
    H, D = random_reduced(3)
    x = np.linspace(0.0, 1.0, 7)
    assert np.allclose(H @ x, D @ x)  # forms the transposes and the factors of cY
    for G in (H.T, 2.0 * H, H @ sp.identity(7, format="csr")):
        assert G._core is H._core
    other, D2 = random_reduced(4)
    total = H + other  # a new core (stacked states): its own cache
    assert total._core is not H._core
    assert np.allclose(total @ x, (D + D2) @ x)
    assert np.allclose(total.T @ x, (D + D2).T @ x)
    Auu, AyuT, Ayu, Ayy = H.abs_core()
    assert np.allclose(Ayu.toarray(), np.abs(H.Lyu.toarray()))
    assert np.allclose(AyuT.toarray(), np.abs(H.Lyu.toarray()).T)


@pytest.mark.parametrize("lower", [True, False])
@pytest.mark.parametrize("p, m", [(9, 8), (80, 90)])  # (80, 90): columns wider than 64
def test_core_matmat_with_triangular_and_general_state_equations(lower, p, m):
    """K Q by the transposed solves equals K applied to Q's columns, for a triangular cY
    (row-by-row substitution) and a general one (its sparse LU)."""
    H, _ = random_reduced(6, p=p, m=m)
    cY = H.cY.toarray()
    if not lower:
        cY = cY + np.triu(np.full_like(cY, 1.0 / m), 1)
    K = ReducedHessian(H.Luu, H.Lyu, H.Lyy, sp.csr_matrix(cY), H.cU)
    Q = sp.random(p, 5, density=0.4, random_state=2, format="csr")
    want = K.core_matvec(Q.toarray())
    for block in (2, 64):
        got = K.core_matmat(Q, block=block)
        assert np.linalg.norm(got - want) <= 1e-12 * np.linalg.norm(want)
    assert (K._core["rows"] is False) is (not lower)


@pytest.mark.parametrize("dtype", [float, np.longdouble])
def test_block_sparse_products_equal_the_assembled_matrix(dtype):
    rng = np.random.default_rng(5)
    blk = lambda m, n, fmt: sp.random(m, n, density=0.4, random_state=rng, format=fmt)
    blocks = [[blk(3, 4, "csr"), None, blk(3, 2, "coo")],
              [None, blk(5, 5, "csc"), None],
              [blk(2, 4, "csr"), blk(2, 5, "csr"), sp.identity(2)]]
    B = BlockSparse(blocks).astype(dtype)
    A = sp.bmat(blocks).toarray()
    assert B.shape == A.shape == (10, 11) and B.tocsr().shape == B.tocsc().shape == A.shape
    assert np.allclose(B.tocsc().toarray(), A)
    X = rng.standard_normal((11, 3)).astype(dtype)
    assert (B @ X).dtype == np.dtype(dtype) and (B @ X[:, 0]).shape == (10,)
    assert np.allclose((B @ X).astype(float), A @ X.astype(float))
    with pytest.raises(ValueError, match="every block row and column"):
        BlockSparse([[sp.identity(2), None], [None, None]])


def test_block_sparse_partial_products_and_wide_blocks():
    rng = np.random.default_rng(6)
    wide_blk = sp.random(4, 40, density=0.5, random_state=rng, format="csr")  # ~20 per row
    blocks = [[sp.identity(4, format="csr"), wide_blk], [None, sp.identity(40, format="csr")]]
    B = BlockSparse(blocks)
    wide = B.wide(entries_per_row=10)
    assert wide.tolist() == [[False, True], [False, False]]
    X = rng.standard_normal((44, 3))
    A = sp.bmat(blocks).toarray()
    # the two masks split the product; each part is the product of its blocks alone
    assert np.allclose(B.product(X, wide) + B.product(X, ~wide), A @ X)
    assert np.allclose(B.product(X, wide)[:4], wide_blk @ X[4:])
    assert np.all(B.product(X, wide)[4:] == 0)
    # float64 blocks times an extended-precision x: widened exactly, no rounding to float64
    Xl = X.astype(np.longdouble) * (1 + np.longdouble(2.0) ** -60)
    assert B.product(Xl, ~wide).dtype == np.longdouble
    assert np.all(B.product(Xl, ~wide)[:4] == Xl[:4])


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


def _random_matrix(seed, n=9):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A[np.abs(A) < 0.8] = 0.0  # sparse enough for SuperLU to pivot and permute
    return A + np.diag(rng.choice([-3.0, 3.0], n))


@pytest.mark.parametrize("seed", range(6))
def test_det_sign_and_solve_dense_sparse_bordered(seed):
    A = _random_matrix(seed)
    sign = int(np.sign(np.linalg.det(A)))
    b = np.random.default_rng(seed + 10).standard_normal(A.shape[0])
    for F in (factorize(A), factorize(sp.csc_matrix(A)),
              factorize(sp.csc_matrix(A), permc_spec="NATURAL")):
        assert F.det_sign() == sign
        assert np.allclose(A @ F.solve(b), b, atol=1e-12 * np.abs(b).max())
    # bordered: [[C, B1], [B2, D]] with the last two rows and columns as the border
    C, B1, B2, D = A[:-2, :-2], A[:-2, -2:], A[-2:, :-2], A[-2:, -2:]
    if abs(np.linalg.det(C)) > 1e-8:
        F = factorize(sp.csc_matrix(C), B1, B2, D)
        assert F.det_sign() == sign
        assert np.allclose(A @ F.solve(b), b, atol=1e-10 * np.abs(b).max())
        # the same core with a border whose determinant has the other sign
        G = F.with_border(B1, B2, D + 1e3 * np.diag([1.0, -1.0]))
        flipped = A.copy()
        flipped[-2:, -2:] = D + 1e3 * np.diag([1.0, -1.0])
        assert G.det_sign() == int(np.sign(np.linalg.det(flipped)))


def test_permutation_parity():
    rng = np.random.default_rng(0)
    for _ in range(20):
        p = rng.permutation(7)
        assert permutation_parity(p) == int(round(np.linalg.det(np.eye(7)[p])))


def test_factorize_reports_singular_and_non_finite_matrices():
    with pytest.raises(np.linalg.LinAlgError):
        factorize(np.ones((3, 3)) * [1.0, 1.0, 0.0])
    with pytest.raises(np.linalg.LinAlgError):
        factorize(sp.csc_matrix(np.diag([1.0, 0.0, 2.0])))
    with pytest.raises(np.linalg.LinAlgError, match="non-finite"):
        factorize(np.diag([1.0, np.nan]))
    with pytest.raises(np.linalg.LinAlgError, match="non-finite"):
        factorize(sp.csc_matrix(np.diag([1.0, np.inf])))


@pytest.mark.parametrize("store", [True, False])
def test_low_rank_update_solves_the_updated_matrix(store):
    rng = np.random.default_rng(3)
    n = 12
    A = sp.diags([rng.uniform(2, 3, n), rng.uniform(-0.5, 0.5, n - 1)], [0, 1]).tocsc()
    rows, cols = np.array([2, 7, 9]), np.array([0, 1, 5, 11])
    C = rng.standard_normal((3, 4))
    M = A.toarray()
    M[np.ix_(rows, cols)] += C
    b = rng.standard_normal((n, 2))
    x = LowRankUpdate(factorize(A), rows, C, cols, store=store).solve(b)
    assert np.allclose(M @ x, b, atol=1e-12)
    # all columns (cols=None): a dense row
    full = rng.standard_normal((1, n))
    M1 = A.toarray()
    M1[4] += full[0]
    assert np.allclose(M1 @ LowRankUpdate(factorize(A), [4], full, store=store).solve(b[:, 0]),
                       b[:, 0], atol=1e-12)
    with pytest.raises(ValueError, match="shape"):
        LowRankUpdate(factorize(A), rows, C[:, :3], cols)


def test_approximation_errors_follow_the_algebra():
    """An approximated part's error estimate |l^T dK u| survives sums, multiples and products."""
    H, _ = random_reduced(11)
    H2, _ = random_reduced(12, m=4)
    calls = []

    def f(l, u):  # a stand-in estimate: |l^T u|, recording the domain it is given
        calls.append(l.shape)
        return np.abs(np.sum(l * u, axis=0))

    H.approximations = (f,)
    rng = np.random.default_rng(3)
    psi = rng.standard_normal((7, 2))
    l, u = H.left.T @ psi, H.right @ psi
    assert np.allclose(H.approximation_error(l, u), np.abs(np.sum(l * u, axis=0)))
    assert np.allclose(H2.approximation_error(l, u), 0.0)  # none: zero
    # scaled: l = Lf^T psi carries the factor, the estimate is evaluated on it
    H3 = 2.0 * H
    assert H3.approximations == (f,)
    # sparse products on either side keep K (and its domain)
    D = sp.diags(rng.uniform(1, 2, 7))
    assert (D @ H).approximations == (f,) and (H @ D).approximations == (f,)
    # same scaling: one domain; different: the stacked domain, f sees its own part
    same = H + ReducedHessian(H2.Luu, H2.Lyu, H2.Lyy, H2.cY, H2.cU, left=H.left)
    assert same.approximations == (f,)
    stacked = H2 + H
    assert stacked.Luu.shape == (14, 14)
    big = rng.standard_normal((14, 2))
    calls.clear()
    got = stacked.approximation_error(big, big)
    assert calls == [(7, 2)]
    assert np.allclose(got, np.abs(np.sum(big[7:] * big[7:], axis=0)))
    # the count of coarse (compressed) state rows is carried the same way
    H.coarse_states = 3
    assert (2.0 * H).coarse_states == (D @ H).coarse_states == (H @ D).coarse_states == 3
    assert (H2 + H).coarse_states == (H + H).coarse_states - 3 == 3
