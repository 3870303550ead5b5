import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.curve import polygon_self_intersects
from tests.helpers import fitted_order, skew_curve, trillium


@pytest.mark.parametrize("grid", [Fourier(33), FiniteDifference(64)])
def test_circle_exact(grid):
    c = Curve.circle(2.5, grid, center=(1.0, -2.0))
    assert np.allclose(c.kappa, 0.4)
    assert np.abs(c.closure()).max() < 1e-12
    x, y = c.positions()
    assert np.allclose(np.hypot(x - 1.0, y + 2.0), 2.5, atol=1e-2 if grid.sparse else 1e-12)
    assert c.length() == pytest.approx(2 * np.pi * 2.5)
    # outward normal, counter-clockwise tangent
    n = c.normal()
    tol = 1e-2 if grid.sparse else 1e-12
    assert np.allclose(n[0] * (x - 1.0) + n[1] * (y + 2.0), 2.5, atol=tol)


def test_polar_curvature_exact_fourier():
    # N = 257 resolves the curvature of this trillium to ~1e-11
    # r = 1 + 0.2 cos 3phi: compare curvature with the closed form at the recovered angles
    c = trillium(257)
    x, y = c.positions()
    phi = np.arctan2(y, x)
    r = 1 + 0.2 * np.cos(3 * phi)
    r1, r2 = -0.6 * np.sin(3 * phi), -1.8 * np.cos(3 * phi)
    k = (r**2 + 2 * r1**2 - r * r2) / (r**2 + r1**2) ** 1.5
    assert np.abs(c.kappa - k).max() < 1e-10
    assert np.abs(np.hypot(x, y) - r).max() < 1e-10
    assert np.ptp(c.g) == 0
    assert np.abs(c.closure()).max() < 1e-10


def test_polar_curvature_converges_fd():
    """Curvature from FD positions (the paper's preprocessing) converges at order 2."""
    Ns = [64, 128, 256, 512]
    errs = []
    for N in Ns:
        c = trillium(N, kind=FiniteDifference)
        x, y = c.positions()
        D, D2 = c.grid.derivative(), c.grid.second_derivative()
        xs, ys, xss, yss = D @ x, D @ y, D2 @ x, D2 @ y
        k_fd = (xs * yss - ys * xss) / (xs**2 + ys**2) ** 1.5
        errs.append(np.abs(k_fd - c.kappa).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_from_positions_closure_converges_fd():
    Ns = [128, 256, 512, 1024]
    errs = []
    for N in Ns:
        t = 2 * np.pi * np.arange(N) / N
        r = 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(4 * t)
        c = Curve.from_positions(r * np.cos(t), r * np.sin(t), FiniteDifference(N))
        errs.append(np.abs(c.closure()).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_from_positions_fourier_spectral():
    t = 2 * np.pi * np.arange(200) / 200
    r = 1 + 0.3 * np.cos(3 * t)
    c = Curve.from_positions(r * np.cos(t), r * np.sin(t), Fourier(257))
    ref = Curve.polar(lambda p: 1 + 0.3 * np.cos(3 * p), Fourier(257))
    assert np.abs(c.closure()).max() < 1e-10
    assert abs(c.length() - ref.length()) < 1e-12
    assert np.abs(c.kappa - ref.kappa).max() < 1e-9
    assert c.positions()[:, 0] == pytest.approx([1.3, 0.0])


def test_immutable_copies():
    c = trillium(33)
    with pytest.raises(ValueError):
        c.kappa[0] = 1.0
    c2 = c.with_kappa(c.kappa * 2)
    assert c2 is not c and np.allclose(c2.kappa, 2 * c.kappa) and np.array_equal(c2.g, c.g)
    c3 = c.with_g(c.g * 2)
    assert c3.length() == pytest.approx(2 * c.length())
    assert np.allclose(c.with_U(c.U).kappa, c.kappa)


def test_self_intersection():
    assert not skew_curve(Fourier(65)).self_intersects()
    t = 2 * np.pi * np.arange(200) / 200
    # a limacon with an inner loop crosses itself
    r = 0.5 + np.cos(t)
    assert polygon_self_intersects(r * np.cos(t), r * np.sin(t))
    # figure eight
    assert polygon_self_intersects(np.sin(t), np.sin(t) * np.cos(t))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(kappa=[np.nan] * 16, g=1.0), "kappa"),
        (dict(kappa=np.ones(16), g=np.inf), "g"),
        (dict(kappa=np.ones(16), g=-1.0), "g"),
        (dict(kappa=np.ones(16), g=np.zeros(16)), "g"),
        (dict(kappa=np.ones(15), g=1.0), "kappa"),
        (dict(kappa=np.ones(16), g=np.ones(17)), "g"),
    ],
)
def test_bad_state(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Curve(grid=FiniteDifference(16), **kwargs)


def test_bad_constructors():
    with pytest.raises(ValueError, match="R"):
        Curve.circle(-1.0, Fourier(17))
    with pytest.raises(ValueError, match="not closed"):
        t = np.linspace(0, np.pi, 50)
        Curve.from_positions(np.cos(t), np.sin(t), Fourier(33))
    with pytest.raises(ValueError, match="clockwise"):
        t = 2 * np.pi * np.arange(50) / 50
        Curve.from_positions(np.cos(t), -np.sin(t), Fourier(33))
    with pytest.raises(ValueError, match="r"):
        Curve.polar(lambda p: -np.ones_like(p), Fourier(17))
    with pytest.raises(ValueError, match="grid"):
        Curve(np.ones(16), 1.0, grid=16)
