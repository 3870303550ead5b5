"""Heteroclinic splices: closure solve, free parameters, corner turning, residual scaling."""

import numpy as np
import pytest

from qsa.equilibria.splice import SpliceProfile, polygon_positions, splice, splice_polygon

K = 5.0
TRIANGLE = [2 * np.pi / 3] * 3


def test_closure_solve_from_perturbed_positions():
    p, L = polygon_positions([np.pi / 2] * 4, [1.0, 0.8, 1.0, 0.8], K)
    rng = np.random.default_rng(1)
    p = p + 0.02 * rng.standard_normal(p.size)
    eq = splice(p, 0.1, length=L, kstar=K)
    assert eq.success, eq.message
    hist = eq.extra["closure_history"]
    assert hist[0] > 1e-3 and hist[-1] <= 1e-12
    assert eq.closure <= 1e-12  # the curve on the output grid closes too
    # Gauss-Newton on an underdetermined system: quadratic convergence
    for a, b in zip(hist[1:-1], hist[2:], strict=False):
        if a < 1e-3:
            assert b <= 50 * a**2 + 1e-14


def test_free_directions():
    p, L = polygon_positions([np.pi / 2] * 4, [1.0, 0.7, 1.0, 0.7], K)
    eq = splice(p, 0.1, length=L, kstar=K)
    V = eq.extra["free_directions"]
    n = p.size
    assert V.shape == (n - 4, n)
    assert np.allclose(V @ V.T, np.eye(n - 4), atol=1e-12)
    assert np.allclose(V @ np.ones(n), 0, atol=1e-12)
    base = np.array(eq.params["positions"])
    prof = eq.extra["profile"]
    eps = 1e-4

    def closure(q):
        return splice(q, 0.1, length=L, kstar=K, solve=False,
                      cutoff=(prof.l1, prof.l2)).extra["closure_history"][0]

    # moving along a free direction breaks closure only at second order
    assert closure(base + eps * V[0]) < 1e-2 * eps
    # moving one front alone breaks it at first order
    e = np.zeros(n)
    e[0] = 1.0
    assert closure(base + eps * e) > 0.5 * K * eps


def test_each_corner_turns_by_kstar_times_its_arc():
    angles = [np.pi / 2, 3 * np.pi / 4, 3 * np.pi / 4]  # rounded right isosceles triangle
    eq = splice_polygon(angles, [1.0, 1.4, 1.0], 0.15, kstar=K)
    prof = eq.extra["profile"]
    p, L = np.array(eq.params["positions"]), eq.params["L"]
    s = np.arange(20001) * L / 20001
    for i in range(3):  # the bump of corner i alone, integrated over the whole circle
        corner = SpliceProfile(prof.front, p[2 * i:2 * i + 2], L, (prof.l1, prof.l2))
        turn = corner(s).sum() * L / s.size
        assert turn == pytest.approx(K * (p[2 * i + 1] - p[2 * i]), rel=1e-12)
    assert prof(s).sum() * L / s.size == pytest.approx(2 * np.pi, rel=1e-13)
    assert eq.params["angles"] == pytest.approx(angles)
    assert eq.closure <= 1e-12


def test_double_residuals_agree_with_mpmath():
    eq = splice_polygon(TRIANGLE, [1.0, 1.0, 1.0], 0.1, kstar=K)
    prof = eq.extra["profile"]
    s = np.linspace(0, eq.params["L"], 37)
    Rk, _ = prof.residuals(s)
    Rmp = np.array([float(v) for v in prof.residual_kappa_mp(s, dps=30)])
    assert np.max(np.abs(Rk - Rmp)) < 1e-10


def test_residual_scaling_with_alpha():
    """log R_kappa against 1/alpha has slope -kstar d_min / sqrt(2) (MATH.md section 5)."""
    alphas = np.array([0.03, 0.035, 0.04, 0.05])
    logR = []
    for alpha in alphas:
        eq = splice_polygon(TRIANGLE, [1.0, 1.0, 1.0], alpha, kstar=K, cutoff=(1.0, 1.5))
        p = np.array(eq.params["positions"])
        s = np.linspace(p[0], p[1], 41)[1:-1]  # the shortest gap: a corner arc
        R = max(abs(v) for v in eq.extra["profile"].residual_kappa_mp(s, dps=50))
        logR.append(float(np.log(float(R))))
        d_min = eq.params["d_min"]
    slope = np.polyfit(1 / alphas, logR, 1)[0]
    assert slope == pytest.approx(-K * d_min / np.sqrt(2), rel=0.01)


def test_fixed_cutoff_keeps_residual_exponentially_small():
    """With the cutoff at fixed arc length, max|R_kappa| falls with alpha."""
    r = [np.max(np.abs(splice_polygon(TRIANGLE, [1.0] * 3, a, kstar=K).extra["R_kappa"]))
         for a in (0.1, 0.07)]
    assert r[1] < 1e-2 * r[0]


def test_invalid_requests():
    with pytest.raises(ValueError, match="sum to 2 pi"):
        splice_polygon([1.0, 1.0, 1.0], [1.0] * 3, 0.1, kstar=K)
    with pytest.raises(ValueError, match="positive"):
        splice_polygon(TRIANGLE, [1.0, -1.0, 1.0], 0.1, kstar=K)
    with pytest.raises(ValueError, match="cannot close"):
        splice_polygon([np.pi / 2, 3 * np.pi / 2], [1.0, 1.0], 0.1, kstar=K)
    with pytest.raises(ValueError, match="cannot close"):  # a "D": third facet would be 0
        splice_polygon([np.pi / 2, np.pi, np.pi / 2], [1.0, 1.2, 1.0], 0.1, kstar=K)
    with pytest.raises(ValueError, match="increase"):
        splice([0.0, 0.5, 0.4, 1.0], 0.1, length=3.0, kstar=K)
    with pytest.raises(ValueError, match="length"):
        splice([0.0, 0.5, 1.0, 1.5], 0.1, kstar=K)
    with pytest.raises(ValueError, match="cutoff"):
        splice([0.0, 0.5, 1.0, 1.5], 0.1, length=3.0, kstar=K, cutoff=(1.0, 1.4))
    with pytest.raises(ValueError, match="alpha"):
        splice([0.0, 0.5, 1.0, 1.5], -0.1, length=3.0, kstar=K)


def test_non_quartic_well_splice(sine_well):
    eq = splice_polygon([np.pi / 2] * 4, [1.0] * 4, 0.05, well=sine_well)
    assert eq.success and eq.closure <= 1e-12
    # R_kappa ~ exp(-lambda d_min), lambda = pi sqrt(2A) / (alpha kstar): e^-7.9 here
    lam = np.pi * np.sqrt(2 * sine_well.A) / (0.05 * sine_well.kstar)
    scale = np.max(np.abs(sine_well.dW(np.linspace(0, 5, 101))))
    assert np.max(np.abs(eq.extra["R_kappa"])) < 100 * np.exp(-lam * eq.params["d_min"]) * scale
    with pytest.raises(ValueError, match="quartic"):
        eq.extra["profile"].residual_kappa_mp([0.0])
