"""Shared test utilities: accurate reference quantities and convergence fits."""

import numpy as np

from qsa import Curve, Fourier


def fitted_order(Ns, errors):
    """Slope p of log(error) ~ -p log(N) (least squares)."""
    return -np.polyfit(np.log(np.asarray(Ns, float)), np.log(np.asarray(errors, float)), 1)[0]


def trillium(N_or_grid, amp=0.2, lobes=3, kind=Fourier):
    grid = kind(N_or_grid) if isinstance(N_or_grid, int) else N_or_grid
    return Curve.polar(lambda t: 1 + amp * np.cos(lobes * t), grid)


def random_curve(seed, grid):
    """A random smooth star-shaped closed curve (modes 2..5 of the radius, amplitude 0.08)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(0, 0.08, 4)
    b = rng.normal(0, 0.08, 4)
    return Curve.polar(lambda t: 1 + sum(a[k] * np.cos((k + 2) * t) + b[k] * np.sin((k + 2) * t)
                                         for k in range(4)), grid)


def skew_curve(grid):
    """A smooth closed curve with no symmetry."""
    return Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t) + 0.1 * np.sin(2 * t + 0.3), grid)


def exact_closure(kfun, gfun, theta0=0.0, nf=401, ng=800):
    """C(U) for analytic (kappa(s), g(s)) on [0,1), accurate off the closed manifold.

    theta = theta0 + int_0^s kappa g: a linear part plus a periodic part computed
    spectrally on a fine grid; the non-periodic integrals use Gauss-Legendre.
    """
    grid = Fourier(nf)
    f = kfun(grid.s) * gfun(grid.s)
    mean = f.mean()
    P = grid.cumulative(f - mean)
    x, w = np.polynomial.legendre.leggauss(ng)
    x, w = 0.5 * (x + 1), 0.5 * w
    theta = theta0 + mean * x + grid.interpolate(P, x)
    gx = gfun(x)
    return np.array([w @ (np.cos(theta) * gx), w @ (np.sin(theta) * gx), mean - 2 * np.pi])


def inner(c, a, b):
    """<a, b> = int a b dsigma on stacked (2N,) or nodal (N,) vectors."""
    w = c.dsigma
    if a.shape[0] == 2 * c.N:
        w = np.concatenate([w, w])
    return float(np.sum(a * b * w))


def assert_gradient_matches_energy(E, c, directions, rtol=1e-8):
    """``<nabla_I E, U1>`` against fourth-order central differences of ``E(U + t U1)``."""
    grad = E.gradient(c)
    for U1 in directions:
        d = 1e-6 * np.linalg.norm(c.U) / np.linalg.norm(U1)
        f = lambda t: E.energy(c.with_U(c.U + t * U1))
        num = (-f(2 * d) + 8 * f(d) - 8 * f(-d) + f(-2 * d)) / (12 * d)
        ana = inner(c, grad, U1)
        scale = np.sqrt(inner(c, grad, grad) * inner(c, U1, U1))
        assert abs(num - ana) <= rtol * scale, (num, ana)


def assert_hessian_matches_energy(E, c, directions, rtol=2e-6, column_rtol=1e-7):
    """The Hessian against the energy and the gradient it differentiates.

    ``<H U1, U1>`` against fourth-order second differences of ``E(U + t U1)``; the whole
    column ``W H U1`` (``W = diag(dsigma, dsigma)``) against central differences of the
    Euclidean gradient ``W nabla_I E``; ``W H`` symmetric.
    """
    from qsa.linalg import to_dense

    Hd = to_dense(E.hessian(c))
    W = np.concatenate([c.dsigma, c.dsigma])
    for U1 in directions:
        d = 1e-4 * np.linalg.norm(c.U) / np.linalg.norm(U1)
        f = lambda t: E.energy(c.with_U(c.U + t * U1))
        num = (-f(2 * d) + 16 * f(d) - 30 * f(0) + 16 * f(-d) - f(-2 * d)) / (12 * d**2)
        ana = inner(c, Hd @ U1, U1)
        bound = max(abs(ana), np.abs(Hd).max() * inner(c, U1, U1))
        assert abs(num - ana) <= rtol * bound, (num, ana)
        d = 1e-6 * np.linalg.norm(c.U) / np.linalg.norm(U1)

        def grad_e(t):
            ct = c.with_U(c.U + t * U1)
            return E.gradient(ct) * np.concatenate([ct.dsigma, ct.dsigma])

        col = (grad_e(d) - grad_e(-d)) / (2 * d)
        ref = W * (Hd @ U1)
        assert np.abs(col - ref).max() <= column_rtol * np.abs(ref).max()
    A = W[:, None] * Hd
    assert np.abs(A - A.T).max() <= 1e-12 * np.abs(A).max()


def assert_status_convention(result, messages):
    """The result convention of qsa: ``success == (status >= 0)``, the message starts with
    ``messages[status]`` (the result module's ``MESSAGES`` table)."""
    assert result.status in messages, (result.status, sorted(messages))
    assert bool(result.success) == (result.status >= 0), (result.success, result.status)
    assert result.message.startswith(messages[result.status]), result.message
