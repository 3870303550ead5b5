"""The backends of the front ODE: one interface; the compiled (numba) kernel against numpy.

Tests that need numba skip with a reason when it is not installed.
"""

import sys
from dataclasses import fields

import numpy as np
import pytest

import qsa.reduction
from qsa.equilibria import close_positions
from qsa.paper import SCENARIOS, scenario_splice
from qsa.reduction.backends import FrontEvaluation, NumpyBackend
from qsa.reduction.ode import FrontODE

try:
    import numba  # noqa: F401

    HAVE_NUMBA = True
except ImportError:
    HAVE_NUMBA = False

needs_numba = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed (the 'fast' "
                                 "extra); the numpy backend is tested without it")

ALPHA, KSTAR = 0.1, 5.0


def _splices(name, count=3, seed=0):
    """Random valid splices near a scenario's: perturbed, then closed."""
    eq = scenario_splice(name, ALPHA, KSTAR)
    p, L = np.array(eq.params["positions"]), eq.params["L"]
    cut = tuple(eq.params["cutoff"])
    ode = FrontODE(ALPHA, KSTAR, L, backend="numpy")
    rng = np.random.default_rng(seed)
    out = [p]
    while len(out) < count:
        q = p + 0.03 * rng.standard_normal(p.size)
        try:
            out.append(close_positions(q, ode.front, L, cut)[0])
        except ValueError:
            continue
    return L, cut, out


def test_numba_backend_without_numba_raises(monkeypatch):
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba -> ImportError
    monkeypatch.delitem(sys.modules, "qsa.reduction._kernels", raising=False)
    monkeypatch.delattr(qsa.reduction, "_kernels", raising=False)
    with pytest.raises(ValueError, match="numba"):
        FrontODE(ALPHA, KSTAR, 3.0, backend="numba")
    ode = FrontODE(ALPHA, KSTAR, 3.0)  # auto: falls back to numpy
    assert ode.backend_used == "numpy"
    with pytest.raises(ValueError, match="backend"):
        FrontODE(ALPHA, KSTAR, 3.0, backend="fortran")


@needs_numba
def test_numba_backend_needs_the_quartic_well(monkeypatch):
    import importlib

    het_module = importlib.import_module("qsa.equilibria.heteroclinic")
    monkeypatch.setattr(het_module, "is_quartic", lambda well, kstar: False)
    assert FrontODE(ALPHA, KSTAR, 3.0).backend_used == "numpy"  # auto: quadrature fronts
    with pytest.raises(ValueError, match="quartic"):
        FrontODE(ALPHA, KSTAR, 3.0, backend="numba")


def test_numpy_backend_forced_works():
    L, cut, ps = _splices("short-facet", count=1)
    ode = FrontODE(ALPHA, KSTAR, L, backend="numpy")
    assert ode.backend_used == "numpy"
    v = ode.velocity(ps[0], cut)
    assert np.all(np.isfinite(v)) and abs(v.sum()) < 1e-12


@needs_numba
@pytest.mark.parametrize("name", list(SCENARIOS))
def test_kernel_matches_numpy(name):
    # The kernel's Theta_j is exact and its cumulative integrals are a 16th-order local
    # rule (error ~1e-10 of the spectral ones at 3 nodes per width): everything agrees
    # to round-off amplified by the saddle-point / Newton solves (measured <= 4e-10).
    L, cut, ps = _splices(name)
    fast = {}
    for corr in (None, "newton"):
        for beta in (None, 5.0):
            kw = {"correction": corr, "beta": beta}
            fast[corr, beta] = (FrontODE(ALPHA, KSTAR, L, backend="numpy", **kw),
                                FrontODE(ALPHA, KSTAR, L, backend="numba", **kw))
    for p in ps:
        ref, num = fast[None, None]
        assert num.backend_used == "numba"
        for meth in ("metric", "gradient"):
            a, b = getattr(ref, meth)(p, cut), getattr(num, meth)(p, cut)
            assert np.max(np.abs(a - b)) < 1e-9 * np.max(np.abs(a)), meth
        (Ca, Ja), (Cb, Jb) = ref.constraints(p, cut), num.constraints(p, cut)
        assert np.max(np.abs(Ca - Cb)) < 1e-12 and np.max(np.abs(Ja - Jb)) < 1e-11
        phi_a, w_a = ref.normal_velocities(p, cut)
        phi_b, w_b = num.normal_velocities(p, cut)
        assert np.allclose(w_a, w_b, rtol=1e-14)
        assert np.max(np.abs(phi_a - phi_b)) < 1e-9 * np.max(np.abs(phi_a))
        # the corrected force (the Newton step's banded solve)
        dE_a = fast["newton", None][0].evaluate(p, cut).force
        dE_b = fast["newton", None][1].evaluate(p, cut).force
        assert np.max(np.abs(dE_a - dE_b)) < 1e-8 * np.max(np.abs(dE_a))
        for (corr, beta), (a, b) in fast.items():
            if beta is None:
                va, ma = a.velocity(p, cut, multipliers=True)
                vb, mb = b.velocity(p, cut, multipliers=True)
                assert np.max(np.abs(ma - mb)) < 1e-8 * np.max(np.abs(ma))
            else:
                va = np.append(*a.velocity_length(p, 1.002 * L, cut))
                vb = np.append(*b.velocity_length(p, 1.002 * L, cut))
            assert np.max(np.abs(va - vb)) < 1e-8 * np.max(np.abs(va)), (corr, beta)


@needs_numba
def test_cell_weights_order():
    # the local rule integrates polynomials of degree 2r - 1 exactly, and its error on a
    # smooth periodic function falls like h^(2r)
    from qsa.reduction._kernels import _cumulative, cell_weights, end_weights

    wq = cell_weights(4)
    assert np.isclose(wq.sum(), 0.5, rtol=1e-15)
    errs = []
    for M in (40, 80):
        s = np.arange(M) / M
        F = np.exp(np.sin(2 * np.pi * s))[None, :]
        out = np.empty_like(F)
        _cumulative(F, end_weights(wq), out)
        from scipy.integrate import quad

        ref = np.array([quad(lambda x: np.exp(np.sin(2 * np.pi * x)), 0, si,
                             epsabs=1e-15)[0] for si in s])
        errs.append(np.max(np.abs(out[0] - ref)))
    assert errs[0] / errs[1] > 2 ** 7  # 8th order (r = 4)


@needs_numba
@pytest.mark.parametrize("name,variable,correction", [
    ("short-facet", False, None), ("short-facet", True, None),
    ("short-facet", False, "newton"), ("triangle", False, None)])
def test_integrate_same_collision_both_backends(name, variable, correction):
    L, cut, (p, *_) = _splices(name, count=1)
    opts = {"rtol": 1e-6, "method": "Radau"} if variable else {"rtol": 1e-6}
    times = []
    for backend in ("numpy", "numba"):
        ode = FrontODE(ALPHA, KSTAR, L, backend=backend, beta=5.0 if variable else None,
                       correction=correction)
        r = ode.integrate(p, SCENARIOS[name].t_final, max_collisions=0, **opts)
        times.append(r.first_collision.time)
    assert abs(times[1] / times[0] - 1) < 1e-6


@needs_numba
def test_band_solvers_match_dense():
    # both banded solvers (unpivoted with growth guard, pivoted fallback) on the Newton
    # matrix H of a splice, against a dense solve of the same matrix
    from qsa.reduction._linalg import (
        _back_substitute_1,
        _band_forward_nopivot,
        _band_solve,
        band_rows,
    )
    from qsa.reduction.correction import D2_STENCIL, folded_band

    L, cut, (p, *_) = _splices("short-facet", count=1)
    ode = FrontODE(ALPHA, KSTAR, L, backend="numba", correction="newton")
    M = ode.grid.N
    a2 = ALPHA**2
    rows = band_rows(*folded_band(M, D2_STENCIL))
    perm = folded_band(M, D2_STENCIL)[0]
    f = ode.fields(p, cut)
    kb = (rows.shape[1] - 1) // 3
    A0 = -a2 * (M / L) ** 2 * rows
    A0[:, kb] += ode.front.well.d2W(f.psi)[perm]
    H = np.zeros((M, M))
    for i in range(M):
        for t in range(rows.shape[1]):
            j = i - kb + t
            if 0 <= j < M:
                H[i, j] = A0[i, t]
    assert np.allclose(H, H.T)
    rng = np.random.default_rng(3)
    b = rng.standard_normal((M, 3))
    ref = np.linalg.solve(H, b)
    A, x = A0.copy(), b.copy()
    assert _band_solve(A, kb, x)
    assert np.max(np.abs(x - ref)) < 1e-9 * np.max(np.abs(ref))
    A, x = A0.copy(), b.copy()
    growth = _band_forward_nopivot(A, kb, x)
    assert 1 <= growth < 1e4
    for c in range(3):
        z = x[:, c].copy()
        _back_substitute_1(A, kb, z)
        assert np.max(np.abs(z - ref[:, c])) < 1e-9 * np.max(np.abs(ref))


def _assert_same_evaluation(a, b, solved_tol):
    """Every field of two :class:`FrontEvaluation` s, relative to its largest entry.

    The ingredients agree within 1e-10 (measured <= 4e-11 at valid splices: the kernel's
    local 16th-order cumulative rule against the spectral one); the solved quantities
    (velocity, multipliers, Newton-corrected force) within ``solved_tol`` (measured
    <= 5e-10: round-off amplified by the saddle-point and Newton solves).
    """
    for fld in fields(FrontEvaluation):
        x, y = getattr(a, fld.name), getattr(b, fld.name)
        assert x.shape == y.shape, fld.name
        if fld.name == "closure":  # C ~ 1e-15 at a closed splice: absolute
            assert np.max(np.abs(x - y)) < 1e-13
            continue
        tol = solved_tol if fld.name in ("velocity", "multipliers", "force", "rhs") else 1e-10
        scale = np.max(np.abs(x))
        assert np.max(np.abs(x - y)) <= tol * scale, (fld.name, np.max(np.abs(x - y)) / scale)


@needs_numba
@pytest.mark.parametrize("name", list(SCENARIOS))
@pytest.mark.parametrize("correction", [None, "newton"])
@pytest.mark.parametrize("beta", [None, 5.0])
def test_backends_return_the_same_named_evaluation(name, correction, beta):
    L, cut, ps = _splices(name, count=2)
    kw = {"correction": correction, "beta": beta}
    a = FrontODE(ALPHA, KSTAR, L, backend="numpy", **kw)
    b = FrontODE(ALPHA, KSTAR, L, backend="numba", **kw)
    assert a.backend_used == "numpy" and b.backend_used == "numba"
    Lx = None if beta is None else L
    for p in ps:
        ea, eb = a.evaluate(p, cut, Lx), b.evaluate(p, cut, Lx)
        _assert_same_evaluation(ea, eb, 1e-9)
        # the hot path of each backend solves the same system
        for ode, e in ((a, ea), (b, eb)):
            sol = ode.evaluator.velocity(p, cut, Lx, correction == "newton")
            assert np.allclose(sol, np.concatenate([e.velocity, e.multipliers]), rtol=0,
                               atol=1e-12 * np.max(np.abs(sol)))


def test_numpy_backend_is_the_interface():
    """Without numba the numpy backend alone satisfies the interface (no skip)."""
    L, cut, (p, *_) = _splices("short-facet", count=1)
    ode = FrontODE(ALPHA, KSTAR, L, backend="numpy", correction="newton")
    assert isinstance(ode.evaluator, NumpyBackend) and ode.evaluator.name == "numpy"
    e = ode.evaluator.evaluate(p, cut, None, True)
    assert isinstance(e, FrontEvaluation)
    sol = ode.evaluator.velocity(p, cut, None, True)
    assert np.array_equal(sol, np.concatenate([e.velocity, e.multipliers]))
    assert np.array_equal(e.velocity, ode.velocity(p, cut))
    plain = ode.evaluator.evaluate(p, cut, None, False)
    assert np.array_equal(plain.force, ode.gradient(p, cut))
    assert not np.array_equal(plain.force, e.force)  # the correction changes the force
