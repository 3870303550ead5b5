"""The capacitance solve of the shift-invert system of a two-point energy against SuperLU."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa import Curve, FiniteDifference
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.linalg import ReducedHessian, factorize
from qsa.spectra import (
    FactoredNormalOperator,
    certified_eigenpairs,
    lagrange_hessian,
    refinement,
    rigid_normal_basis,
)
from qsa.spectra import capacitance as cap
from qsa.spectra.factored import ShiftInvert


def _operator(N, l_star):
    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t),
                    FiniteDifference(N))
    E = (CanhamHelfrich(0.1) + Perimeter(1.0, 1.2 * c.length())
         + Adhesion(A0=10.0, l_star=l_star, a=1.0))
    LH = lagrange_hessian(E, c, constraints="curvature")
    return c, FactoredNormalOperator.from_lagrangian(c, LH.matrix)


@pytest.fixture
def forced(monkeypatch):
    """Take the capacitance route whatever the size and width."""
    monkeypatch.setattr(cap, "MIN_NODES", 0)
    monkeypatch.setattr(cap, "WIDE_ROW", 0)


@pytest.fixture
def never(monkeypatch):
    monkeypatch.setattr(cap, "WIDE_ROW", np.inf)


def test_core_matmat_is_core_matvec_of_the_dense_columns():
    _, op = _operator(160, 0.1)
    K = op.reduced
    Q = sp.random(K.Luu.shape[0], 37, density=0.02, random_state=1, format="csr")
    want = K.core_matvec(Q.toarray())
    got = K.core_matmat(Q, block=50)
    assert np.linalg.norm(got - want) <= 1e-12 * np.linalg.norm(want)


@pytest.mark.parametrize("sigma", [0.0, -3.0, 40.0])
def test_capacitance_solves_the_whole_core(forced, sigma):
    c, op = _operator(200, 0.1)
    si = ShiftInvert(op, sigma)
    assert si.core_solver == "capacitance"
    core = si._core.tocsc()
    n = core.shape[0]
    b = np.random.default_rng(2).standard_normal((n, 3))
    x = si._lu._solve(b)  # the core alone, without the border
    ref = spla.splu(sp.csc_matrix(core)).solve(b)
    assert np.linalg.norm(x - ref) <= 1e-9 * np.linalg.norm(ref)
    assert si._lu._core_sign() == factorize(core).det_sign()


def test_eigenpairs_agree_between_the_two_core_solvers(monkeypatch):
    # above the dense-inverse limit: ARPACK, on unrefined capacitance solves then polished
    c, op = _operator(440, 0.1)
    rigid = op.ritz(rigid_normal_basis(c))[0]
    out = {}
    for route, (nodes, width) in {"superlu": (10**9, np.inf), "capacitance": (0, 0)}.items():
        monkeypatch.setattr(cap, "MIN_NODES", nodes)
        monkeypatch.setattr(cap, "WIDE_ROW", width)
        assert op.shift_invert(0.0).core_solver == route
        out[route] = certified_eigenpairs(op, np.zeros((0, c.N)), k=8, sigma=0.0, rigid=rigid)
    a, b = out["superlu"], out["capacitance"]
    assert a.method == b.method == "factored shift-invert"
    assert np.all(b.errors <= 1e-8 * np.maximum(np.abs(b.values), 1.0))
    assert np.allclose(np.sort(a.values), np.sort(b.values), rtol=0,
                       atol=float(np.max(a.errors + b.errors)))


def test_route_follows_the_width_of_the_two_point_blocks():
    _, narrow = _operator(cap.MIN_NODES, 0.01)
    _, wide = _operator(cap.MIN_NODES, 0.15)
    assert not cap.use_capacitance(narrow.reduced, narrow.N)
    assert cap.use_capacitance(wide.reduced, wide.N)
    assert narrow.shift_invert(0.0).core_solver == "superlu"
    assert wide.shift_invert(0.0).core_solver == "capacitance"


def test_unrefined_solve_returns_phi_of_the_refined_one(forced):
    c, op = _operator(200, 0.1)
    R = np.linalg.qr((rigid_normal_basis(c) * np.sqrt(c.dsigma)).T)[0].T / np.sqrt(c.dsigma)
    si = ShiftInvert(op, 0.5, deflate=R)
    b = c.dsigma * np.cos(2 * np.pi * 3 * c.grid.s)
    fine = si.solve(b)
    quick = si.solve(b, refine=0)  # phi and psi only, through the border
    assert np.linalg.norm(quick - fine) <= 1e-7 * np.linalg.norm(fine)
    assert not si._capacitance.phi_only
    assert np.abs(R @ (c.dsigma * quick)).max() <= 1e-8 * np.abs(quick).max()


def _full_solution(si, b):
    """The refined solution of the whole bordered system for ``b`` (as ``solve`` makes it)."""
    p = si._B1.shape[1]
    rhs = np.zeros((si._system.n + p,) + b.shape[1:])
    rhs[: si.op.N] = b
    x = si._lu.solve(rhs)
    return rhs, x + si._lu.solve(si._system.residual(rhs, x, p))


@pytest.mark.parametrize("mixed", [True, False])
def test_forward_error_estimate_covers_the_extended_precision_correction(forced, monkeypatch,
                                                                         mixed):
    monkeypatch.setattr(refinement, "MIXED_NOISE", np.inf if mixed else 0.0)
    c, op = _operator(300, 0.1)
    si = ShiftInvert(op, 0.0)
    assert si._system.wide is not None
    w = c.dsigma
    s = c.grid.s
    B = np.column_stack([w * np.cos(2 * np.pi * j * s) for j in range(2, 8)]
                        + [w * np.random.default_rng(4).standard_normal(c.N)])
    si.solve(B, estimate=True)
    found = si._probe(si._lu, si._B1.shape[1])
    assert not found.extended and found.mixed is mixed
    assert 0 < found.noise < 1e-12 and 0 < found.accuracy < 1e-12
    # the correction with the whole residual in extended precision
    p = si._B1.shape[1]
    rhs, x = _full_solution(si, B)
    dx = si._lu.solve(si._system.residual(rhs, x, p, "extended"))
    ext = np.sqrt(np.sum(w[:, None] * dx[: c.N] ** 2, axis=0))
    if not mixed:  # the extended correction itself
        assert np.allclose(si.last_correction, ext, rtol=1e-12, atol=0)
        return
    assert np.all(si.last_correction >= ext)
    # the wide blocks in working precision move the correction by the probe's noise level
    dxw = si._lu.solve(si._system.residual(rhs, x, p, "mixed"))
    moved = np.sqrt(np.sum(w[:, None] * (dxw - dx)[: c.N] ** 2, axis=0))
    xn = np.sqrt(np.sum(w[:, None] * x[: c.N] ** 2, axis=0))
    assert np.all(moved <= 2 * found.noise * xn)


def test_ritz_pairs_errors_equal_those_of_a_second_solve(forced):
    c, op = _operator(300, 0.1)
    R = np.linalg.qr((rigid_normal_basis(c) * np.sqrt(c.dsigma)).T)[0].T / np.sqrt(c.dsigma)
    si = ShiftInvert(op, 0.0, deflate=R)
    w, rw = c.dsigma, np.sqrt(c.dsigma)[:, None]
    s = c.grid.s
    V = np.column_stack([np.cos(2 * np.pi * j * s) for j in range(2, 10)])
    V -= R.T @ (R @ (w[:, None] * V))
    X = np.linalg.qr(rw * si.solve(w[:, None] * V))[0] / rw
    X = np.linalg.qr(rw * si.solve(w[:, None] * X))[0] / rw  # two steps towards the slowest
    vals, vecs, err = si.ritz_pairs(X)
    assert np.allclose(np.sum(w[:, None] * vecs**2, axis=0), 1.0)
    # the errors from the combined solve are those of a fresh solve of the Ritz vectors
    again = si.errors(vals, vecs)
    # (not yet converged: the residuals are far above the solves' forward errors)
    assert np.all(err.residual > 1e-8 * np.abs(vals))
    assert np.allclose(err.residual, again.residual, rtol=1e-6)
    assert np.allclose(err.rounding, again.rounding, rtol=1e-6)
    # kernel_ritz: Rayleigh-Ritz of the inverse without the deflation, on span R
    kv, kvec, kerr = si.kernel_ritz(R)
    A = R @ (w[:, None] * si.solve_free(w[:, None] * R.T))
    nu = np.linalg.eigvalsh(0.5 * (A + A.T))
    assert np.allclose(kv, si.sigma + 1.0 / nu, rtol=1e-10, atol=0)
    assert kvec.shape == (c.N, R.shape[0]) and np.all(kerr > 0)
    assert np.array_equal(op.ritz_values(R), op.ritz(R)[0])


def test_wide_rows_confined_to_a_small_block_stay_with_the_sparse_lu():
    """A dense trailing block of fewer than N state rows (a compressed pair term's coarse
    state) is factored by SuperLU; wide rows over the whole state take the capacitance."""
    N, q, r = 500, 1500, 480
    rng = np.random.default_rng(0)
    dense = rng.standard_normal((r, r))
    Lyy = sp.block_diag([sp.identity(q - r), sp.csr_matrix(dense + dense.T)], format="csr")
    K = ReducedHessian(sp.identity(2 * N), sp.csr_matrix((q, 2 * N)), Lyy, sp.identity(q),
                       sp.csr_matrix((q, 2 * N)))
    assert K.Lyy.nnz >= cap.WIDE_ROW * q  # wide on average
    assert not cap.use_capacitance(K, N)
    wide = sp.csr_matrix(sp.random(q, q, density=0.2, random_state=1))
    K2 = ReducedHessian(sp.identity(2 * N), sp.csr_matrix((q, 2 * N)), wide + wide.T,
                        sp.identity(q), sp.csr_matrix((q, 2 * N)))
    assert cap.use_capacitance(K2, N)
    # more wide rows than N, all of them the coarse state of a compressed term: sparse LU
    big = rng.standard_normal((2 * N, 2 * N))
    K3 = ReducedHessian(sp.identity(2 * N), sp.csr_matrix((2 * N, 2 * N)),
                        sp.csr_matrix(big + big.T), sp.identity(2 * N),
                        sp.csr_matrix((2 * N, 2 * N)))
    assert cap.use_capacitance(K3, N)
    K3.coarse_states = 2 * N
    assert not cap.use_capacitance(K3, N)
