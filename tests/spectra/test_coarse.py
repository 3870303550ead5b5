"""The coarse Schur solver of the shift-invert core (qsa.spectra.coarse)."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa import Curve, FiniteDifference
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.energies import adhesion as ad
from qsa.linalg.lu import _superlu_sign
from qsa.spectra import factored, lagrange_hessian, spectrum
from qsa.spectra.coarse import CoarseSchurCore
from qsa.spectra.factored import FactoredNormalOperator


def _energy(c, l_star=0.5):
    return (CanhamHelfrich(0.08) + Perimeter(60.0, 1.1 * c.length())
            + Adhesion(40.0, l_star, 1.0, method="neighbours"))


@pytest.fixture(scope="module")
def compressed():
    """A shift-invert factorization whose pair Hessian is panel-interpolated."""
    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t),
                    FiniteDifference(1000))
    E = _energy(c)
    mp = pytest.MonkeyPatch()
    mp.setattr(ad, "INTERPOLATE_PAIRS", 0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            op = FactoredNormalOperator.from_lagrangian(c, lagrange_hessian(E, c).matrix)
    finally:
        mp.undo()
    return c, E, op


def _parts(op, sigma=0.3):
    si = op.shift_invert(sigma)
    K = op.reduced
    return si, si._core.tocsr(), op.N, K.Luu.shape[0], K.cY.shape[0], K.coarse_index


def test_the_coarse_route_solves_the_whole_core(compressed):
    c, E, op = compressed
    si, core, N, p, q, coarse = _parts(op)
    assert si.core_solver == "coarse" and coarse.size > 0
    solver = CoarseSchurCore(core, N, p, q, coarse)
    b = np.random.default_rng(0).standard_normal((core.shape[0], 3))
    x = solver.solve(b)
    ref = spla.splu(core.tocsc()).solve(b)
    # one refinement step against the core (as ShiftInvert does) reaches the LU solution
    x = x + solver.solve(b - core @ x)
    assert np.linalg.norm(x - ref) <= 1e-8 * np.linalg.norm(ref)
    one = solver.solve(b[:, 0])
    assert np.linalg.norm(one - solver.solve(b)[:, 0]) <= 1e-12 * np.linalg.norm(one)
    # the determinant's sign is that of the sparse LU of the whole core
    assert solver.det_sign() == _superlu_sign(spla.splu(core.tocsc()))
    assert solver.nnz > solver._C.nnz and 0 < solver.interface < N


@pytest.mark.parametrize("chunks", [2, 7])
def test_any_number_of_chunks_gives_the_same_elimination(compressed, chunks):
    c, E, op = compressed
    si, core, N, p, q, coarse = _parts(op)
    b = np.random.default_rng(1).standard_normal(core.shape[0])
    a = CoarseSchurCore(core, N, p, q, coarse)
    k = CoarseSchurCore(core, N, p, q, coarse, chunks=chunks)
    xa, xk = a.solve(b), k.solve(b)
    assert np.linalg.norm(xa - xk) <= 1e-6 * np.linalg.norm(xa)
    ra = np.linalg.norm(b - core @ xa)
    assert np.linalg.norm(b - core @ xk) <= 10 * ra + 1e-12 * np.linalg.norm(b)


def test_a_core_of_another_structure_is_refused(compressed):
    c, E, op = compressed
    si, core, N, p, q, coarse = _parts(op)
    bad = core.tolil()
    z = 3 * N + 2 * p + coarse[0]
    bad[z, 0] = 1.0  # a coarse row that reads a narrow unknown
    with pytest.raises(ValueError, match="coarse rows"):
        CoarseSchurCore(bad.tocsr(), N, p, q, coarse)
    with pytest.raises(ValueError, match="expected"):
        CoarseSchurCore(core[:-1, :-1], N, p, q, coarse)
    with pytest.raises(ValueError, match="no coarse state"):
        CoarseSchurCore(core, N, p, q, coarse[:0])
    with pytest.raises(ValueError, match="not nodal"):
        CoarseSchurCore(core, N, p + 1, q - 1, coarse)


def test_spectra_agree_between_the_coarse_and_the_sparse_lu_routes(compressed, monkeypatch):
    c, E, op = compressed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        monkeypatch.setattr(ad, "INTERPOLATE_PAIRS", 0)
        coarse = spectrum(E, c, k=6)

        class Refuse:
            def __init__(self, *args, **kwargs):
                raise ValueError("refused")

        monkeypatch.setattr(factored, "CoarseSchurCore", Refuse)
        assert op.shift_invert(0.0).core_solver == "superlu"
        whole = spectrum(E, c, k=6)
    assert np.all(np.abs(coarse.eigenvalues - whole.eigenvalues)
                  <= coarse.errors + whole.errors)
    assert np.allclose(coarse.eigenvalues, whole.eigenvalues, rtol=0, atol=1e-8)


def test_the_coarse_rows_keep_their_place_through_sums():
    """ReducedHessian sums stack the states: the coarse rows of the second term move."""
    from qsa.linalg import ReducedHessian

    def rh(q, coarse):
        K = ReducedHessian(sp.identity(4), sp.csr_matrix((q, 4)), sp.identity(q),
                           sp.identity(q), sp.csr_matrix((q, 4)))
        K.coarse_index = np.asarray(coarse, dtype=np.intp)
        K.coarse_states = len(coarse)
        return K

    s = rh(5, [3, 4]) + rh(6, [1])
    assert s.coarse_index.tolist() == [3, 4, 6] and s.coarse_states == 3
    assert (2.0 * s).coarse_index.tolist() == [3, 4, 6]


def test_the_probe_measures_the_unrefined_error(compressed):
    """The probe's first refinement step sizes an unrefined solve's forward error; through
    the coarse state it is small enough for ARPACK to run on unrefined solves."""
    from qsa.spectra.refinement import column_norms
    from qsa.spectra.solvers import UNREFINED

    c, E, op = compressed
    si = op.shift_invert(0.0)
    w = op.w
    b = w[:, None] * np.random.default_rng(2).standard_normal((op.N, 3))
    x0, x2 = si.solve(b, refine=0), si.solve(b, refine=2)
    actual = np.max(column_norms(x0 - x2, w) / column_norms(x2, w))
    est = si.unrefined_error()
    assert 0 < est <= UNREFINED
    assert est / 30 <= actual <= 30 * est


def test_a_dense_constraint_term_keeps_the_compression_estimate(compressed, monkeypatch):
    """An area constraint's Hessian is dense, so the Lagrangian Hessian is formed densely:
    the compressed pair term's error estimate must still join the eigenvalues' errors."""
    from qsa.constraints import FixedArea

    c, E, op = compressed
    cons = [FixedArea(c.area())]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = spectrum(E, c, k=6, constraints=cons)
        monkeypatch.setattr(ad, "INTERPOLATE_PAIRS", 0)
        LH = lagrange_hessian(E, c, constraints=cons)
        approx = spectrum(E, c, k=6, constraints=cons)
    assert isinstance(LH.matrix, np.ndarray) and LH.energy_hessian.approximations
    kept = FactoredNormalOperator.from_lagrangian(c, LH.matrix, LH.energy_hessian)
    assert kept.approximated is not None
    assert FactoredNormalOperator.from_lagrangian(c, LH.matrix).approximated is None
    diff = np.abs(approx.eigenvalues - exact.eigenvalues)
    assert np.all(diff <= approx.errors + exact.errors)
    assert np.all(approx.errors > exact.errors)


@pytest.mark.parametrize("gauge", ["comoving", "scaled"])
def test_the_dense_gauges_take_the_exact_pair_hessian(compressed, monkeypatch, gauge):
    """The comoving and scaled operators are dense and carry no compression estimate:
    they are formed with the exact pair Hessian even when the spectra's is compressed."""
    from qsa.spectra import linearization

    c, E, op = compressed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = linearization(E, c, gauge)
        monkeypatch.setattr(ad, "INTERPOLATE_PAIRS", 0)
        LH = lagrange_hessian(E, c)
        assert LH.energy_hessian.approximations
        from_compressed = linearization(E, c, gauge, lagrange=LH)
    ex = exact.toarray() if hasattr(exact, "toarray") else np.asarray(exact)
    fc = (from_compressed.toarray() if hasattr(from_compressed, "toarray")
          else np.asarray(from_compressed))
    assert np.abs(ex - fc).max() <= 1e-10 * np.abs(ex).max()


def test_the_compression_is_chosen_by_its_rank_before_any_build(monkeypatch):
    """From INTERPOLATE_PAIRS pairs on, the compressed form is taken when coarse_rank
    (the panels alone) is below N; a state of higher rank is not compressed at all."""
    from qsa.energies import adhesion_interp

    builds = []
    real = adhesion_interp.interpolated_pair_hessian

    def counting(*args, **kwargs):
        builds.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(adhesion_interp, "interpolated_pair_hessian", counting)
    # a long-range kernel on a smooth curve: few panels
    c = Curve.polar(lambda t: 1 + 0.25 * np.cos(4 * t), FiniteDifference(1300))
    A = Adhesion(40.0, 0.5, 1.0, method="neighbours")
    assert ad.adhesion_pairs(A.kernel, *c.positions())[0].size >= ad.INTERPOLATE_PAIRS
    assert adhesion_interp.coarse_rank(A.kernel, c) < c.N
    H = A.factored_hessian(c)
    assert H.approximations and H.coarse_index.size and builds
    # a short-range kernel on a wiggly curve: many panels, rank above N
    builds.clear()
    wiggly = Curve.polar(lambda t: 1 + 0.1 * np.cos(25 * t), FiniteDifference(300))
    B = Adhesion(40.0, 0.05, 1.0, method="neighbours")
    monkeypatch.setattr(ad, "INTERPOLATE_PAIRS", 0)
    assert adhesion_interp.coarse_rank(B.kernel, wiggly) >= wiggly.N
    assert not getattr(B.factored_hessian(wiggly), "approximations", ())
    assert not builds
