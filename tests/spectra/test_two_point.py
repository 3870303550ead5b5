"""Spectra with a two-point (adhesion) energy: the implicit-state Hessian in the factored solve."""

import warnings

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.linalg import ReducedHessian, to_dense
from qsa.spectra import (
    FactoredNormalOperator,
    certified_eigenpairs,
    lagrange_hessian,
    rigid_normal_basis,
    spectrum,
)


def _cha(c, l_star):
    return (CanhamHelfrich(0.1) + Perimeter(1.0, 1.2 * c.length())
            + Adhesion(A0=10.0, l_star=l_star, a=1.0))


@pytest.mark.parametrize("N, l_star", [(240, 0.05), (600, 0.1)])
def test_reduced_hessian_solves_agree_with_the_formed_matrix(N, l_star):
    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t),
                    FiniteDifference(N))
    LH = lagrange_hessian(_cha(c, l_star), c, constraints="curvature")
    assert isinstance(LH.matrix, ReducedHessian)
    op = FactoredNormalOperator.from_lagrangian(c, LH.matrix)
    assert op.reduced is not None
    Jd = to_dense(op.form())
    x = np.random.default_rng(0).standard_normal(N)
    assert np.linalg.norm(op.matvec(x) - Jd @ x) <= 1e-12 * np.linalg.norm(Jd @ x)
    rigid = op.ritz(rigid_normal_basis(c))[0]
    sol = certified_eigenpairs(op, np.zeros((0, N)), k=8, sigma=0.0, rigid=rigid)
    dense = np.linalg.eigvals(Jd).real
    for lam, err in zip(sol.values, sol.errors, strict=False):
        near = dense[np.argmin(np.abs(dense - lam))]
        # the formed matrix's own round-off is eps |J|: the certified value lies within it
        assert abs(near - lam) <= err + 1e-13 * np.max(np.abs(dense))
        assert err <= 1e-8 * max(abs(lam), 1.0)


@pytest.mark.parametrize("grid", [Fourier(129), FiniteDifference(400)])
def test_spectrum_accepts_canham_helfrich_adhesion(grid):
    c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # not an equilibrium: the operator at the curve
        s = spectrum(_cha(c, 0.1), c, k=6)
    assert s.success and s.eigenvalues.size == 6
    assert np.all(s.errors <= 1e-6 * np.maximum(np.abs(s.eigenvalues), 1.0))


@pytest.mark.parametrize("grid", [Fourier(65), FiniteDifference(200)])
def test_lagrangian_and_energy_hessians_are_self_adjoint_for_the_kernel_report_norms(grid):
    # the kernel report takes their norms by Lanczos, which needs <.,.>-self-adjointness
    from qsa.spectra import operator_norm

    c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        LH = lagrange_hessian(_cha(c, 0.3), c)
    w2 = np.concatenate([c.dsigma, c.dsigma])
    X = np.random.default_rng(1).standard_normal((2 * c.N, 2))
    for A in (LH.matrix, LH.energy_hessian):
        AX = A @ X
        assert abs(X[:, 0] @ (w2 * AX[:, 1]) - X[:, 1] @ (w2 * AX[:, 0])) <= 1e-10 * np.abs(
            X[:, 0] @ (w2 * AX[:, 1]))
        lanczos = operator_norm(c, A, iters=8, symmetric=True)
        assert abs(lanczos - operator_norm(c, A, iters=30)) <= 1e-3 * lanczos


def test_interpolated_pair_hessian_gives_the_assembled_spectrum(monkeypatch):
    """With many pairs, the spectrum takes the panel-interpolated pair Hessian (coarse state
    of rank 3M < N, factored by the sparse LU): the same eigenvalues as the assembled
    blocks, within error estimates that now carry the compression's estimate."""
    from qsa.energies import adhesion as ad
    from qsa.energies.adhesion_interp import interpolated_hessian

    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t),
                    FiniteDifference(1000))
    E = _cha(c, 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = spectrum(E, c, k=6)
        monkeypatch.setattr(ad, "INTERPOLATE_PAIRS", 0)
        H = E.terms()[-1].factored_hessian(c)
        approx = spectrum(E, c, k=6)
    assert H.approximations and H.cY.shape[0] > 3 * c.N  # the extended (coarse) state
    assert H.cY.shape[0] - 3 * c.N < c.N
    assert np.allclose(approx.eigenvalues, exact.eigenvalues, rtol=0, atol=1e-8)
    diff = np.abs(approx.eigenvalues - exact.eigenvalues)
    assert np.all(diff <= approx.errors + exact.errors)
    assert np.all(approx.errors > exact.errors)  # the compression's estimate is included
    # the estimate of a form's change is zero without compression and positive with it
    u = np.random.default_rng(1).standard_normal((2 * c.N, 2))
    assert np.all(H.approximation_error(u, u) > 0)
    # a state whose coarse rank is not below N is left to the assembled blocks
    assert interpolated_hessian(E.terms()[-1].kernel, c, max_rank=10) is None
