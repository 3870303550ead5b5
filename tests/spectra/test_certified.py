"""Slow eigenvalues at every resolution: the factored operator, its error estimates.

The 3-pulse equilibrium of Faceting(alpha = 0.15, kstar = 5) + Perimeter: its slow
eigenvalues (the kernel, the unstable coarsening pair, the breathing mode) from the
formed matrix J drown in round-off ``eps |J| ~ N^6``; from the factors they are right
at every N. Reference: the smallest resolving Fourier grid.
"""

import warnings

import numpy as np
import pytest

from qsa import FiniteDifference, Fourier
from qsa.equilibria import npulse, polish, splice_polygon
from qsa.spectra import (
    MESSAGES,
    FactoredNormalOperator,
    lagrange_hessian,
    normal_operator,
    rigid_normal_basis,
    spectrum,
)
from tests.helpers import assert_status_convention

ALPHA = 0.15


def _nonkernel(s, n=None):
    """Non-kernel eigenvalues nearest 0 with their errors (sorted by |lambda|)."""
    lam, err = s.eigenvalues[~s.is_kernel], s.errors[~s.is_kernel]
    order = np.argsort(np.abs(lam), kind="stable")[:n]
    return lam[order], err[order]


@pytest.fixture(scope="module")
def reference():
    eq = npulse(3, ALPHA)
    assert eq.curve.N < 300 and eq.residual < 1e-6
    s = spectrum(eq.energy, eq.curve, k=23)
    assert s.status == 0 and s.n_kernel == 3 and s.n_unstable == 2
    return s


def test_reference_errors_are_tiny_and_the_pair_is_double(reference):
    lam, err = _nonkernel(reference, 20)
    assert np.all(err[:6] <= 1e-8 * np.abs(lam[:6])) and np.all(err <= 1e-5 * np.abs(lam))
    assert lam[0] == pytest.approx(lam[1], rel=1e-9)  # D3 symmetry: a double pair
    # the rigid eigenvalues sit at the level of the equilibrium's residual
    kern = reference.eigenvalues[reference.is_kernel]
    assert np.max(np.abs(kern)) < 1e-4 * lam[0]


def test_fourier_at_higher_resolution_agrees_with_the_reference(reference):
    eq = npulse(3, ALPHA, grid=Fourier(511))
    s = spectrum(eq.energy, eq.curve, k=23)
    assert s.status == 0 and s.n_kernel == 3 and s.n_unstable == 2
    lam, err = _nonkernel(s, 20)
    ref, _ = _nonkernel(reference, 20)
    assert np.all(np.abs(lam - ref) <= 1e-7 * np.abs(ref))
    assert np.max(np.abs(s.eigenvalues[s.is_kernel])) < 1e-4 * lam[0]
    # the formed matrix at this N cannot resolve them: its round-off is far larger
    assert s.roundoff > 1e3 * err[0]


def test_finite_differences_converge_at_second_order(reference):
    ref, _ = _nonkernel(reference, 6)
    Ns = (999, 1998, 3999)
    errs = []
    for N in Ns:
        eq = npulse(3, ALPHA, grid=FiniteDifference(N))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # FD quasi-equilibrium of the Fourier one
            p = polish(eq.energy, eq.curve)
        assert p.success
        s = spectrum(p.energy, p.curve, k=9)
        assert s.n_kernel == 3 and s.n_unstable == 2 and s.unresolved.size == 0
        lam, err = _nonkernel(s, 6)
        assert np.all(err < 1e-3 * np.abs(lam - ref))  # round-off far below the FD error
        errs.append(np.max(np.abs(lam - ref) / np.abs(ref)))
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.2)


def test_finite_differences_at_ten_thousand_nodes(reference):
    eq = npulse(3, ALPHA, grid=FiniteDifference(9999))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = polish(eq.energy, eq.curve)
    assert p.success
    s = spectrum(p.energy, p.curve, k=20)
    assert s.n_kernel == 3 and s.n_unstable == 2 and s.eigenvalues.size == 20
    lam, err = _nonkernel(s, 17)
    ref, _ = _nonkernel(reference, 17)
    assert np.all(np.abs(lam - ref) <= 1e-3 * np.abs(ref))
    assert np.all(err <= 1e-6 * np.abs(lam))


def test_shift_invert_equals_dense_and_does_not_depend_on_sigma():
    eq = npulse(3, 0.1)
    dense = spectrum(eq.energy, eq.curve, reject_spurious=False)
    ref, rerr = _nonkernel(dense, 3)
    for sigma in (0.0, 0.5, -1.0, -150.0):
        s = spectrum(eq.energy, eq.curve, k=8, sigma=sigma)
        lam, err = _nonkernel(s, 3)
        assert np.all(np.abs(lam - ref) <= 1e-8 * np.abs(ref))
        assert np.all(np.abs(lam - ref) <= 2 * (err + rerr) + 1e-14 * np.abs(ref))
    # the formed matrix gets the double coarsening eigenvalue wrong by far more than
    # its own error bound eps |J| allows for the certified value
    formed = np.linalg.eigvals(normal_operator(eq.energy, eq.curve)).real
    near = formed[np.argmin(np.abs(formed - ref[0]))]
    assert abs(near - ref[0]) > 100 * rerr[0]


def test_error_estimates_bound_the_extended_precision_eigenvalues():
    """The discrete pencil (W J, W) from the float64 factors, solved at 40 digits."""
    mpmath = pytest.importorskip("mpmath")
    eq = npulse(2, 0.45)
    assert eq.curve.N < 60
    c = eq.curve
    LH = lagrange_hessian(eq.energy, c)
    op = FactoredNormalOperator.from_lagrangian(c, LH.matrix)
    s = spectrum(eq.energy, c, k=8)
    with mpmath.workdps(40):
        M1 = mpmath.matrix(np.vstack([op.G, np.diag(op.gk)]).tolist())
        H = mpmath.matrix(op.H.tolist())
        A = -(M1.T * (H * M1))
        rw = [mpmath.sqrt(mpmath.mpf(x)) for x in op.w]
        B = mpmath.matrix(c.N, c.N)
        for i in range(c.N):
            for j in range(c.N):
                B[i, j] = (A[i, j] + A[j, i]) / 2 / (rw[i] * rw[j])
        exact = np.array([float(x) for x in mpmath.eigsy(B, eigvals_only=True)])
    for lam, err, kern in zip(s.eigenvalues, s.errors, s.is_kernel, strict=False):
        if kern:
            continue
        nearest = exact[np.argmin(np.abs(exact - lam))]
        assert abs(lam - nearest) <= err


def test_polished_splice_slow_pair_does_not_depend_on_N():
    pairs = []
    for N in (285, 511):
        eq = splice_polygon(np.radians([120, 120, 120]), [0.35] * 3, 0.1, kstar=5.0,
                            grid=Fourier(N))
        p = polish(eq.energy, eq.curve)
        assert p.success
        s = spectrum(p.energy, p.curve, k=8)
        assert s.n_kernel == 3 and s.n_unstable == 2
        pairs.append(_nonkernel(s, 2)[0])
    assert np.allclose(pairs[0], pairs[1], rtol=1e-6)


def test_rigid_modes_are_deflated_exactly():
    eq = npulse(3, ALPHA, grid=Fourier(189))
    c = eq.curve
    s = spectrum(eq.energy, c, k=10)
    R = rigid_normal_basis(c)
    V = s.eigenvectors[:, ~s.is_kernel]
    overlap = R @ (c.dsigma[:, None] * V)
    assert np.max(np.abs(overlap)) < 1e-10
    G = s.eigenvectors.T @ (c.dsigma[:, None] * s.eigenvectors)
    assert np.allclose(G, np.eye(G.shape[0]), atol=1e-8)


def test_unresolved_eigenvalues_are_flagged_not_reported():
    from qsa.spectra import UnresolvedEigenvalueWarning

    eq = npulse(3, ALPHA, grid=Fourier(189))
    with pytest.warns(UnresolvedEigenvalueWarning, match="failed the accuracy test"):
        s = spectrum(eq.energy, eq.curve, k=12, rtol=1e-14)
    assert s.status == 2 and s.unresolved.size > 0
    assert_status_convention(s, MESSAGES)
    assert np.all(s.unresolved_errors > 1e-14 * np.abs(s.unresolved))
    assert np.all((s.errors <= 1e-14 * np.abs(s.eigenvalues)) | s.is_kernel)
