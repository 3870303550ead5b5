"""The slow-manifold (Newton) correction: the kernels alone, and the corrected force."""

import numpy as np
import pytest

from qsa.equilibria import SpliceProfile, default_cutoff, heteroclinic
from qsa.equilibria.splice import polygon_positions
from qsa.paper import scenario_splice
from qsa.reduction.correction import (
    D2_STENCIL,
    folded_band,
    newton_correction,
    newton_correction_dense,
)
from qsa.reduction.manifold import energy_gradient, quadrature_size
from qsa.reduction.ode import FrontODE

ALPHA, KSTAR = 0.1, 5.0


def _square(facet):
    """A rounded square splice (not closed: the kernels do not need it) on its grid."""
    front = heteroclinic(ALPHA, kstar=KSTAR)
    p, L = polygon_positions(np.full(4, np.pi / 2), np.full(4, facet), KSTAR)
    M = quadrature_size(L, front.width, 3.0)
    sigma = L * np.arange(M) / M
    prof = SpliceProfile(front, p, L, default_cutoff(p, L))
    psi, _, d2 = prof(sigma, derivatives=True)
    return front.well, psi, d2, prof.position_derivatives(sigma), L, M


def _off_span(R, B):
    return np.linalg.norm(R - B @ np.linalg.lstsq(B, R, rcond=None)[0])


@pytest.mark.parametrize("M", [9, 10, 31])
def test_folded_band_is_the_periodic_stencil(M):
    perm, ab = folded_band(M, D2_STENCIL)
    kb = 2 * (D2_STENCIL.size - 1)
    assert ab.shape == (3 * kb + 1, M) and ab.flags.f_contiguous
    assert np.array_equal(np.sort(perm), np.arange(M))
    A = np.zeros((M, M))
    for j in range(M):
        for i in range(max(0, j - kb), min(M, j + kb + 1)):
            A[i, j] = ab[2 * kb + i - j, j]
    assert not np.any(ab[:kb])  # the fill-in rows start empty
    P = sum(D2_STENCIL[abs(d)] * np.roll(np.eye(M), d, axis=1) for d in range(-4, 5))
    assert np.array_equal(A, P[np.ix_(perm, perm)])
    # 8th order: exact on polynomials of degree 9 away from the seam, unit spacing
    x = np.arange(M, dtype=float)
    assert abs((P @ x**9)[M // 2] - 72 * x[M // 2] ** 7) < 1e-7 * x[M // 2] ** 7


def test_banded_solve_equals_dense_solve():
    """The banded LU + Schur complement against a dense solve of the same bordered system."""
    well, psi, d2, B, L, M = _square(0.25)
    delta, R = newton_correction(psi, d2, B, L, ALPHA, well, folded_band(M, D2_STENCIL))
    D = sum(D2_STENCIL[abs(d)] * np.roll(np.eye(M), d, axis=1) for d in range(-4, 5))
    H = -(ALPHA**2) * (M / L) ** 2 * D + np.diag(well.d2W(psi))
    Bc = np.column_stack([B, np.ones(M)])
    nb = Bc.shape[1]
    K = np.block([[H, Bc], [Bc.T, np.zeros((nb, nb))]])
    R0 = -(ALPHA**2) * d2 + well.dW(psi)
    x = np.linalg.solve(K, np.concatenate([-R0, np.zeros(nb)]))
    d_ref, mu = x[:M], x[M:]
    R_ref = well.dW(psi + d_ref) - well.dW(psi) - well.d2W(psi) * d_ref - Bc @ mu
    assert np.max(np.abs(delta - d_ref)) < 1e-10 * np.max(np.abs(d_ref))
    assert np.max(np.abs(R - R_ref)) < 1e-10 * np.max(np.abs(R_ref))
    assert np.max(np.abs(Bc.T @ delta)) < 1e-12 * np.max(np.abs(delta))


def test_newton_step_cuts_the_profile_residual_quadratically():
    """One step: the residual of the profile equation (off the slow directions) squares.

    The residual of ``psi + delta`` is recomputed independently (spectral ``d^2``), over a
    sweep of facet lengths; ``log |R_1|`` against ``log |R_0|`` has slope 2.
    """
    r0, r1 = [], []
    for facet in (0.15, 0.2, 0.25, 0.3, 0.4):
        well, psi, d2, B, L, M = _square(facet)
        delta, R = newton_correction(psi, d2, B, L, ALPHA, well, folded_band(M, D2_STENCIL))
        kw = 2 * np.pi * np.fft.fftfreq(M, d=L / M)
        d2delta = np.fft.ifft(-(kw**2) * np.fft.fft(delta)).real
        R1 = -(ALPHA**2) * (d2 + d2delta) + well.dW(psi + delta)
        Bc = np.column_stack([B, np.ones(M)])
        r0.append(_off_span(-(ALPHA**2) * d2 + well.dW(psi), Bc))
        r1.append(_off_span(R1, Bc))
        assert _off_span(R, Bc) == pytest.approx(r1[-1], rel=2e-3)  # R is that residual
    assert np.all(np.array(r1) < 0.06 * np.array(r0))
    slope = np.polyfit(np.log(r0), np.log(r1), 1)[0]
    assert abs(slope - 2) < 0.2


def test_slow_correction_is_a_newton_step(triangle):
    """``delta`` keeps positions and turning, and cuts the residual off span(B) quadratically."""
    ode, p, cut = triangle
    f = ode.fields(p, cut)
    delta, Rc = ode.slow_correction(p, cut)
    B = np.column_stack([f.dpsi_dp, np.ones(delta.size)])
    assert np.max(np.abs(B.T @ delta)) < 1e-9 * np.max(np.abs(B.T @ np.abs(delta)))

    def off_span(R):
        return np.linalg.norm(R - B @ np.linalg.lstsq(B, R, rcond=None)[0])

    R0 = -(ALPHA**2) * f.d2psi + ode.front.well.dW(f.psi)
    assert off_span(Rc) < 1e-3 * off_span(R0)
    # the correction is the (small) nonlinear response to the overlapping tails
    assert 0 < np.max(np.abs(delta)) < 1e-2 * KSTAR


def _correction_errors(ppw, state):
    eq = scenario_splice(state)
    p, L, cut = np.array(eq.params["positions"]), eq.params["L"], tuple(eq.params["cutoff"])
    ode = FrontODE(ALPHA, KSTAR, L, correction="newton", points_per_width=ppw)
    if state == "short-facet":  # late state: the short facet near its collision
        r = ode.integrate(p, 0.09, rtol=1e-5, max_collisions=0)
        p = r.segments[0].p[-2]
    f = ode.fields(p, cut)
    well = ode.front.well
    d_ref, R_ref = newton_correction_dense(f.psi, f.d2psi, f.dpsi_dp, L, ALPHA, well)
    delta, R = newton_correction(f.psi, f.d2psi, f.dpsi_dp, L, ALPHA, well,
                                 folded_band(ode.grid.N, D2_STENCIL))
    F_ref, F = energy_gradient(f, ALPHA, well, R_ref), energy_gradient(f, ALPHA, well, R)
    shift = np.max(np.abs(F_ref - energy_gradient(f, ALPHA, well)))  # what it changes
    return (np.max(np.abs(delta - d_ref)) / np.max(np.abs(d_ref)),
            np.max(np.abs(F - F_ref)) / shift, shift / np.max(np.abs(F_ref)), ode.grid.N)


@pytest.mark.parametrize("state", ["triangle", "short-facet"])
def test_banded_correction_matches_dense_spectral(state):
    """The banded 8th-order solve against the dense spectral one (the former default).

    At the default 3 points per front width the difference error of ``d^2`` is
    ``~(h lambda)^8 / 560``-small for the smooth ``delta``: ``delta`` within 1e-5 and the
    force correction within 1e-4 of the spectral one (far below the 1e-2 the corrected
    rate is accurate to); a finer grid cuts the difference of ``delta`` like ``h^8``
    (fitted order > 6). The force difference falls as fast at first, but at 6 points per
    width it meets the dense reference's own round-off (1e-6..4e-6 of the shift,
    depending on the BLAS), so for it only a decrease faster than ``h^2`` is asserted.
    """
    e_delta, e_force, shift, M = _correction_errors(3, state)
    assert e_delta < 1e-5 and e_force < 1e-4
    assert shift > 1e-4  # the correction itself is resolved far above these errors
    fine = _correction_errors(6, state)
    ratio = fine[3] / M
    assert fine[0] < e_delta / ratio**6 and fine[1] < e_force / ratio**2


def test_newton_correction_matches_dae_collision_time():
    """Short facet: the corrected force closes the facet at the DAE's (stiff-perimeter) rate."""
    from qsa import FiniteDifference
    from qsa.flows import FacetingFlow, solve_flow
    from qsa.reduction.fronts import detect_fronts, track_flow

    eq = scenario_splice("short-facet", ALPHA, KSTAR, grid=FiniteDifference(600))
    p, L = np.array(eq.params["positions"]), eq.params["L"]

    def stop(t, y, system):
        return detect_fronts(system.curvature(y), KSTAR, system.length(y)).n < p.size

    res = solve_flow(FacetingFlow(ALPHA, KSTAR, 500.0, L), eq.curve.positions(), 0.09, N=600,
                     tol=1e-6, method="bdf2", callback=stop, progress=False)
    tc_dae = track_flow(res, KSTAR).first_collision.time
    tc = {c: FrontODE(ALPHA, KSTAR, L, correction=c).integrate(
        p, 0.09, rtol=1e-4, max_collisions=0).first_collision.time for c in (None, "newton")}
    assert abs(tc["newton"] / tc_dae - 1) < 0.01
    assert abs(tc[None] / tc_dae - 1) > 0.015  # the splice's own force is measurably slower



def test_singular_newton_matrix_falls_back_to_least_squares():
    """``H = 0`` (no stiffness, a flat well): the banded LU fails, the dense bordered
    matrix is singular too; least squares returns the zero step, no NaN."""

    class Flat:
        def dW(self, x):
            return np.zeros_like(x)

        def d2W(self, x):
            return np.zeros_like(x)

    M, L = 15, 1.0
    psi = np.full(M, 1.0)
    B = np.cos(2 * np.pi * np.arange(M) / M)[:, None]
    for delta, R in (newton_correction(psi, np.zeros(M), B, L, 0.0, Flat(),
                                       folded_band(M, D2_STENCIL)),
                     newton_correction_dense(psi, np.zeros(M), B, L, 0.0, Flat())):
        assert np.all(np.isfinite(delta)) and np.max(np.abs(delta)) < 1e-12
        assert np.all(np.isfinite(R)) and np.max(np.abs(R)) < 1e-12
