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
    """log R_kappa against 1/alpha has slope -kstar d_min / sqrt(2) (Conventions, section 5)."""
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


def test_paper_cutoff_scaling_with_alpha_gives_alpha_independent_error():
    """The paper's cutoff |s| in [alpha l, 2 alpha l] leaves R ~ exp(-kstar l / sqrt 2)."""
    from qsa.equilibria import heteroclinic

    ell = 2.0
    p, L = polygon_positions(TRIANGLE, [1.0] * 3, K)
    s = np.linspace(0, L, 20001)
    r = []
    for alpha in (0.04, 0.06):
        prof = SpliceProfile(heteroclinic(alpha, kstar=K), p, L, (alpha * ell, 2 * alpha * ell))
        r.append(np.max(np.abs(prof.residuals(s)[0])))
    assert r[1] == pytest.approx(r[0], rel=0.05)  # no decay with alpha
    assert r[0] > 1e-3  # far above the fixed-cutoff residual ~ exp(-lambda d_min) ~ 1e-11


def _cut_front_cases():
    x = np.concatenate([np.linspace(-2.6, 2.6, 2001), [0.0, 1.0, -1.0, 2.0, -2.0]])
    return x, (1.0, 2.0)


def test_cut_front_derivatives_match_differences(sine_well):
    """``psi~'`` and ``psi~''`` against central differences, across the cutoff band."""
    from qsa.equilibria import heteroclinic

    x, cut = _cut_front_cases()
    x = x[(np.abs(np.abs(x) - 1.0) > 1e-3) & (np.abs(np.abs(x) - 2.0) > 1e-3)]  # C^inf, but
    for front in (heteroclinic(0.3, kstar=K), heteroclinic(0.3, sine_well)):  # steep there
        prof = SpliceProfile(front, [0.0, 1.0, 2.0, 3.0], 8.0, cut)
        v0, v1, v2 = prof.cut_front(x)
        h = 1e-5
        p0, p1, _ = prof.cut_front(x + h)
        m0, m1, _ = prof.cut_front(x - h)
        assert np.max(np.abs((p0 - m0) / (2 * h) - v1)) < 1e-6 * np.max(np.abs(v1))
        assert np.max(np.abs((p1 - m1) / (2 * h) - v2)) < 1e-6 * np.max(np.abs(v2))
        band = (np.abs(x) > 1.0) & (np.abs(x) < 2.0)
        assert np.max(np.abs(v0[band] - front.kstar * (x[band] > 0))) > 0  # the cutoff acts
        assert np.all(v0[np.abs(x) >= 2.0] == front.kstar * (x[np.abs(x) >= 2.0] > 0))


def test_cut_front_closed_form_equals_quadrature_path(monkeypatch):
    """The logistic closed form against the same quartic front built by quadrature."""
    import importlib

    from qsa.equilibria import heteroclinic

    x, cut = _cut_front_cases()
    exact = SpliceProfile(heteroclinic(0.3, kstar=K), [0.0, 1.0], 8.0, cut)
    het_module = importlib.import_module("qsa.equilibria.heteroclinic")
    monkeypatch.setattr(het_module, "is_quartic", lambda well, kstar: False)
    quad = SpliceProfile(heteroclinic(0.3, kstar=K), [0.0, 1.0], 8.0, cut)
    assert exact.front.closed_form and not quad.front.closed_form
    for a, b in zip(exact.cut_front(x), quad.cut_front(x), strict=True):
        assert np.max(np.abs(a - b)) < 1e-10 * np.max(np.abs(a))
    # shapes are kept (scalars, matrices)
    assert exact.cut_front(0.5)[0].shape == ()
    assert exact.cut_front(np.ones((3, 2)))[2].shape == (3, 2)
