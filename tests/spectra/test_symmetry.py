"""Bloch-sector spectra: circles (closed form, mode labels), N-pulses (exact pairs), FD (ARPACK)."""

import warnings

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.equilibria import circle, npulse, polish
from qsa.spectra import spectrum
from qsa.spectra.symmetry import (
    BlochSymmetry,
    detect_symmetry,
    sector_basis,
    sector_spectrum,
)
from tests.reference.circle_spectra import faceting_circle_eigenvalues


def test_circle_sectors_are_the_modes_of_the_closed_form():
    R, alpha, kstar, beta, N = 0.7, 0.1, 5.0, 5.0, 33
    eq = circle(R, alpha, grid=Fourier(N), beta=beta, kstar=kstar)
    s = sector_spectrum(eq.energy, eq.curve)
    _, lam = faceting_circle_eigenvalues(R, alpha, kstar, beta, (N - 1) // 2)
    assert s.symmetry.circle and s.complete
    # one entry per mode m != 1 (mode 1 = translations = the kernel), modes >= 2 double
    assert sorted(s.sector.tolist()) == [0] + list(range(2, 17))
    for lam_i, m, mult, err in zip(s.eigenvalues, s.sector, s.multiplicity, s.errors,
                                   strict=True):
        assert lam_i == pytest.approx(lam[m], rel=1e-9)
        assert mult == (1 if m == 0 else 2) and err <= 1e-9 * abs(lam_i)
    assert s.kernel.size == 2 and np.all(np.abs(s.kernel) < 1e-8)
    # the closed form's unstable count
    assert s.n_unstable == int(lam[0] > 0) + 2 * int(np.sum(lam[2:] > 0)) > 0
    # the eigenvector of mode m is exp(2 pi i m s)
    i = int(np.flatnonzero(s.sector == 3)[0])
    v = s.vectors[:, i]
    e = np.exp(2j * np.pi * 3 * eq.curve.grid.s)
    assert abs(abs(np.vdot(e, v)) / (np.linalg.norm(e) * np.linalg.norm(v)) - 1) < 1e-12


@pytest.mark.parametrize("n, grid", [(3, Fourier(99)), (4, FiniteDifference(200))])
def test_npulse_blocks_reproduce_the_full_spectrum_with_exact_pairs(n, grid):
    """(Odd Fourier grids hold no even symmetry order: the 4-pulse is on finite differences.)"""
    eq = npulse(n, 0.15, grid=grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eq = polish(eq.energy, eq.curve)
    assert eq.relative_residual < 1e-9
    s = sector_spectrum(eq.energy, eq.curve)
    assert s.symmetry.order == n and s.symmetry.reflection is not None
    full = spectrum(eq.energy, eq.curve, reject_spurious=False)
    assert np.repeat(s.eigenvalues, s.multiplicity).size == np.sum(~full.is_kernel)
    assert s.n_unstable == full.n_unstable
    # the slow eigenvalues against the certified shift-invert ones (same deflation)
    near = spectrum(eq.energy, eq.curve, k=23)
    ref = np.sort(near.eigenvalues[~near.is_kernel])
    mine = np.repeat(s.eigenvalues, s.multiplicity)
    for x in ref:
        assert np.min(np.abs(mine - x)) <= 1e-9 * abs(x)
    # the coarsening pair is the double eigenvalue of Bloch index 1
    top = int(np.argmax(s.eigenvalues))
    assert s.sector[top] == 1 and s.multiplicity[top] == 2
    # real eigenvectors of a pair: orthonormal, both eigenvectors of the Bloch one
    V = s.real_vectors(top)
    G = V.T @ (eq.curve.dsigma[:, None] * V)
    assert np.allclose(G, np.eye(2), atol=1e-10)


def test_large_sectors_use_arpack_and_agree_with_the_shift_invert_spectrum():
    eq = npulse(3, 0.15, grid=FiniteDifference(1500))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = polish(eq.energy, eq.curve)
    s = sector_spectrum(p.energy, p.curve, k=4)
    assert not s.complete and s.symmetry.shift == 500
    ref = spectrum(p.energy, p.curve, k=14)
    lam = ref.eigenvalues[~ref.is_kernel]
    mine = np.repeat(s.eigenvalues, s.multiplicity)
    for x in np.sort(mine)[-4:]:
        assert np.min(np.abs(lam - x)) <= 1e-8 * abs(x)
    with pytest.raises(ValueError, match="pass k"):
        sector_spectrum(p.energy, p.curve)


def test_detection_and_bases():
    c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    assert detect_symmetry(c).order == 3  # resampled to constant g: 3-fold on 33 nodes
    assert detect_symmetry(c.with_g(c.g * (1 + 0.01 * np.sin(c.grid.s)))).order == 1
    eq = npulse(2, 0.3, grid=Fourier(45))
    assert detect_symmetry(eq.curve, tol=1e-8).order == 1  # 2 does not divide 45
    eq = npulse(2, 0.3, grid=FiniteDifference(60))
    sym = detect_symmetry(eq.curve)
    assert sym.order == 2 and sym.multiplicity(1) == 1 and sym.sectors == (0, 1)
    Q = sector_basis(BlochSymmetry(4, 12), 1, np.full(12, 0.5))
    assert np.allclose(Q.conj().T @ (0.5 * Q), np.eye(3))
    with pytest.raises(ValueError, match="symmetry"):
        sector_spectrum(eq.energy, eq.curve, BlochSymmetry(7, 60))
    with pytest.raises(ValueError, match="sectors"):
        sector_spectrum(eq.energy, eq.curve, sectors=[5])
