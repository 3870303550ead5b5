"""The capacitance solve by GMRES, and the reduced Hessian with an operator pair term."""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa import Curve, FiniteDifference
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
from qsa.energies.adhesion_far import hierarchical_pair_hessian
from qsa.energies.adhesion_hessian import adhesion_derivatives
from qsa.spectra import (
    FactoredNormalOperator,
    certified_eigenpairs,
    lagrange_hessian,
    rigid_normal_basis,
)
from qsa.spectra import capacitance as cap
from qsa.spectra.capacitance import CapacitanceCore
from qsa.spectra.capacitance_iterative import IterativeCapacitanceCore
from qsa.spectra.factored import local_blocks

KERNEL = AdhesionKernel(10.0, 0.1, 1.0)
TOL = 1e-10


def _state(N):
    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t),
                    FiniteDifference(N))
    E = (CanhamHelfrich(0.1) + Perimeter(1.0, 1.2 * c.length())
         + Adhesion(A0=KERNEL.A0, l_star=KERNEL.l_star, a=KERNEL.a))
    LH = lagrange_hessian(E, c, constraints="curvature").matrix
    op = FactoredNormalOperator.from_lagrangian(c, LH)
    d = adhesion_derivatives(KERNEL, c, adhesion_pairs(KERNEL, *c.positions()))
    return c, op, d


@pytest.fixture(scope="module")
def state():
    return _state(400)


def test_operator_pair_term_with_the_assembled_pairs_is_the_reduced_hessian(state):
    c, _, d = state
    R = d.reduced_hessian()
    O = d.operator_reduced_hessian(d.pair_hessian())
    X = np.random.default_rng(0).standard_normal((2 * c.N, 3))
    assert np.linalg.norm(O @ X - R @ X) <= 1e-13 * np.linalg.norm(R @ X)
    v, y, mu = O.implicit_state(X[:, 0], 1.0, 2.0, 3.0)
    v0, y0, mu0 = R.implicit_state(X[:, 0], 1.0, 2.0, 3.0)
    for a, b in ((v, v0), (y, y0), (mu, mu0)):
        assert np.linalg.norm(a - b) <= 1e-13 * np.linalg.norm(b)


def test_operator_pair_term_compressed_within_its_tolerance(state):
    c, _, d = state
    R = d.reduced_hessian()
    H = hierarchical_pair_hessian(KERNEL, *c.positions(), c.dsigma, tol=TOL, leaf_size=32)
    assert H.far_factor_entries > 0  # some blocks are compressed
    O = d.operator_reduced_hessian(H)
    X = np.random.default_rng(1).standard_normal((2 * c.N, 3))
    err = np.linalg.norm(O @ X - R @ X) / np.linalg.norm(R @ X)
    assert err <= 10 * TOL


@pytest.mark.parametrize("compressed", [False, True])
def test_gmres_capacitance_solves_like_the_lu(state, compressed):
    c, op, d = state
    K = op.reduced
    if compressed:
        H = hierarchical_pair_hessian(KERNEL, *c.positions(), c.dsigma, tol=TOL, leaf_size=32)
        K = d.operator_reduced_hessian(H).with_left(K.left)
    loc, dgk, N = local_blocks(op, 0.0), sp.diags(op.gk), c.N
    lu = CapacitanceCore(loc, op.reduced, dgk, N)
    it = IterativeCapacitanceCore(loc, K, dgk, N)
    b = np.random.default_rng(2).standard_normal((lu.shape[0], 2))
    want, got = lu.solve(b), it.solve(b)
    assert it.failures == 0 and len(it.iterations) == 2
    # T is well conditioned here (rcond ~ 1e-3): the phi's agree to the GMRES and
    # compression tolerances times its condition
    assert np.linalg.norm(got[:N] - want[:N]) <= 1e-7 * np.linalg.norm(want[:N])
    assert np.linalg.norm(got - want) <= 1e-7 * np.linalg.norm(want)


def test_gmres_capacitance_arguments(state):
    c, op, _ = state
    args = (local_blocks(op, 0.0), op.reduced, sp.diags(op.gk), c.N)
    with pytest.raises(ValueError, match="rtol"):
        IterativeCapacitanceCore(*args, rtol=2.0)
    with pytest.raises(ValueError, match="deflate"):
        IterativeCapacitanceCore(*args, deflate=5, arnoldi=5)
    with pytest.raises(NotImplementedError):
        IterativeCapacitanceCore(*args).det_sign()


def test_deflation_cuts_the_iterations_not_the_solution(state):
    c, op, _ = state
    args = (local_blocks(op, 0.0), op.reduced, sp.diags(op.gk), c.N)
    plain, deflated = IterativeCapacitanceCore(*args), IterativeCapacitanceCore(*args, deflate=60)
    assert deflated.deflated > 0
    b = np.zeros((plain.shape[0], 2))
    b[:c.N] = np.random.default_rng(3).standard_normal((c.N, 2))
    x, y = plain.solve(b), deflated.solve(b)
    assert deflated.failures == 0
    assert max(deflated.iterations) < min(plain.iterations) // 2
    assert np.linalg.norm(x - y) <= 1e-8 * np.linalg.norm(x)


def test_eigenpairs_agree_between_lu_and_gmres_capacitance(monkeypatch):
    # the GMRES route is switched off by default; forced here on a small state
    c, op, _ = _state(440)
    monkeypatch.setattr(cap, "MIN_NODES", 0)
    monkeypatch.setattr(cap, "WIDE_ROW", 0)
    monkeypatch.setattr(cap, "DEFLATE", 60)
    monkeypatch.setattr(cap, "ARNOLDI", 120)
    rigid = op.ritz(rigid_normal_basis(c))[0]
    out = {}
    for route, iterative in (("capacitance", False), ("gmres", True)):
        monkeypatch.setattr(cap, "ITERATIVE", iterative)
        assert op.shift_invert(0.0).core_solver == route
        out[route] = certified_eigenpairs(op, np.zeros((0, c.N)), k=8, sigma=0.0, rigid=rigid)
    a, b = out["capacitance"], out["gmres"]
    assert np.all(b.errors <= 1e-8 * np.maximum(np.abs(b.values), 1.0))
    assert np.allclose(np.sort(a.values), np.sort(b.values), rtol=0,
                       atol=float(np.max(a.errors + b.errors)))


def test_gmres_route_is_off_by_default():
    assert cap.ITERATIVE is False
