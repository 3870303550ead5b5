"""Shared test utilities: test curves and energies, derivative checks, convergence fits,
reference runs used by several test modules (no test module imports another)."""

import json
import math
import os
import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from qsa import Curve, Fourier
from qsa.energies import FirstOrderEnergy, FunctionalizedCurvature, Perimeter, SecondOrderEnergy
from qsa.flows import CHA, FacetingFlow, solve_flow
from qsa.flows.dae import SecondOrderFlow
from qsa.paper import CONVERGENCE, CHAScenario
from qsa.resample import resample_closed
from qsa.studies import npulse_study


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


def coupled_energy():
    """A density with a p-k coupling (F10 != 0) and non-quadratic dependence."""
    return FirstOrderEnergy(
        F=lambda p, k: 0.01 * p**2 + 0.02 * p * k**2 + np.cosh(0.5 * k),
        F_p=lambda p, k: 0.02 * p + 0.02 * k**2,
        F_k=lambda p, k: 0.04 * p * k + 0.5 * np.sinh(0.5 * k),
        F_pp=lambda p, k: 0.02 + 0 * p,
        F_pk=lambda p, k: 0.04 * k,
        F_kk=lambda p, k: 0.04 * p + 0.25 * np.cosh(0.5 * k),
    )


def off_manifold(grid, seed=0):
    """A smooth, non-closed state: a closed curve plus a perturbation of kappa and g."""
    c = skew_curve(grid)
    rng = np.random.default_rng(seed)
    s = grid.s
    dk = 0.2 * rng.standard_normal() * np.cos(2 * np.pi * s + rng.uniform()) + 0.1
    dg = 0.3 * np.sin(4 * np.pi * s + rng.uniform()) * c.g.mean() * 0.2
    return Curve(c.kappa + dk, c.g + dg, grid, c.theta0, c.origin)


def directions(grid, seed):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(3):
        v = rng.standard_normal(2 * grid.N)
        out.append(v / np.linalg.norm(v))
    s = grid.s
    out.append(np.concatenate([np.cos(6 * np.pi * s), 0.5 * np.sin(2 * np.pi * s)]))
    return out


def coupled_second_order(placement="node"):
    """Every partial non-zero somewhere, including the odd couplings F_qp and F_pk."""
    a, b, c = 0.01, 0.03, 0.02

    def F(q, p, k):
        return (0.5 * a * q**2 + b * q * p * k + c * q * k**2 + 0.05 * p**2 * k
                + np.cosh(0.5 * k) + 0.1 * q * np.sin(p))

    def dF(q, p, k):
        return (a * q + b * p * k + c * k**2 + 0.1 * np.sin(p),
                b * q * k + 0.1 * p * k + 0.1 * q * np.cos(p),
                b * q * p + 2 * c * q * k + 0.05 * p**2 + 0.5 * np.sinh(0.5 * k))

    def d2F(q, p, k):
        return (a + 0 * q, b * k + 0.1 * np.cos(p), b * p + 2 * c * k,
                0.1 * k - 0.1 * q * np.sin(p), b * q + 0.1 * p, 2 * c * q + 0.25 * np.cosh(0.5 * k))

    return SecondOrderEnergy(F, dF, d2F, placement=placement)


def paper_curve(N):
    """Equal-chord nodes of the convergence study's start (2000 samples resampled)."""
    x, y, _ = resample_closed(*CONVERGENCE.samples(2000), N, method="chord")
    return x, y


def paper_samples(M=2000):
    return CONVERGENCE.samples(M)


def circle_radius_errors(method, tol, N=48, T=0.5, eps=0.1, beta=1.0, rho=1.5):
    """Max over snapshots of |R_flow(t) - R_ode(t)| for a regular N-gon under CH + penalty.

    A regular N-gon stays regular and its circumradius R obeys dR/dt = V(R) / cos(pi/N),
    V the discrete normal velocity on the N-gon: kappa = |D1 X| |D2 X| / L^3 (stencils),
    D2 kappa = 0, L = 2 N R sin(pi/N).
    """
    th = 2 * np.pi * np.arange(N) / N
    res = solve_flow(CHA(eps=eps, beta=beta, rho=rho), (np.cos(th), np.sin(th)), T, N=N,
                     tol=tol, method=method, t_eval=np.linspace(0, T, 11))
    a = 2 * np.pi / N
    L0 = 2 * N * math.sin(math.pi / N)

    def rhs(t, R):
        L = 2 * N * R * math.sin(math.pi / N)
        d1 = R * math.sin(a) * N
        d2 = 2 * R * (1 - math.cos(a)) * N**2
        kappa = d1 * d2 / L**3
        V = eps * 0.5 * kappa**3 - beta * (L - rho * L0) * kappa
        return V / math.cos(math.pi / N)

    ref = solve_ivp(rhs, (0, T), [1.0], t_eval=res.t, rtol=1e-12, atol=1e-14)
    assert ref.y[0, -1] > 1.1  # the test has teeth: R moved by much more than 10 tol
    errors = []
    for i in range(res.t.size):
        X, Y = res.positions(i)
        r = np.hypot(X - X.mean(), Y - Y.mean())
        assert np.ptp(r) < 1e-8  # still a circle
        errors.append(abs(r.mean() - ref.y[0, i]))
    return max(errors), res


def fd_jacobian(S, x, h=1e-6):
    """Central differences of ``S.residual`` (an equilibrium system) at ``x``."""
    J = np.zeros((x.size, x.size))
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h * max(1.0, abs(x[i]))
        J[:, i] = (S.residual(x + e) - S.residual(x - e)) / (2 * e[i])
    return J


def assert_quadratic_convergence(r, bound=1e3):
    """r_{k+1} / r_k^2 bounded while r_{k+1} is above the round-off floor."""
    h = np.asarray(r.history)
    assert h[-1] <= 1e-10
    floor = 100 * r.noise_floor
    ratios = [h[k + 1] / h[k] ** 2 for k in range(len(h) - 1) if h[k + 1] > floor]
    assert len(ratios) >= 2
    assert max(ratios) < bound, ratios
    # and the last steps gain orders of magnitude
    assert h[-1] < 1e-3 * h[-3]


def slow_study(n_pulses=3, alpha=0.1, delay=0.0):
    """npulse_study that takes at least ``delay`` seconds (so a run can be killed mid-way)."""
    time.sleep(delay)
    out = npulse_study(n_pulses=n_pulses, alpha=alpha)
    out["pid"] = os.getpid()
    return out


def smooth_curve(N, scale=1.3, shift=0.05):
    """Equal-chord nodes of a smooth non-symmetric curve (no symmetry left)."""
    th = 2 * np.pi * np.arange(1000) / 1000
    r = 1 + 0.1 * np.cos(3 * th) + 0.05 * np.sin(2 * th)
    x, y, _ = resample_closed(scale * r * np.cos(th) + shift, scale * r * np.sin(th), N,
                              method="chord")
    return x, y


class SexticWell:
    """A user well (not the quartic default) to exercise the ``well=`` path."""

    def W(self, k):
        return 0.25 * k**2 * (k - 2.0) ** 2 + 0.01 * k**6

    def dW(self, k):
        return 0.5 * k * (k - 2.0) * (2 * k - 2.0) + 0.06 * k**5

    def d2W(self, k):
        return 0.5 * (6 * k**2 - 12 * k + 4.0) + 0.3 * k**4


#: The DAE flow models the flow tests run (adhesion variants, faceting with a user well).
FLOW_MODELS = {
    "cha-neighbours": CHA(**CONVERGENCE.model_params()),
    "cha-dense": CHA(**CONVERGENCE.model_params(), adhesion_method="dense"),
    "cha-centred-normal": CHA(**CONVERGENCE.model_params(), force_normal="centred"),
    "cha-short-kernel": replace(CHAScenario(), l_star=0.35).model(),
    "ch-no-adhesion": CHA(eps=0.1, beta=1.0, rho=1.5),
    "facet": FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0),
    "facet-user-well": FacetingFlow(alpha=0.2, kstar=2.0, beta=1.0, L_star=7.0,
                                    well=SexticWell()),
    "second-order": SecondOrderFlow(FunctionalizedCurvature(0.3, 1.0, 2.0)
                                    + Perimeter(5.0, 6.0)),
}


def numerical_jacobians(sys, y, ydot, d=1e-6):
    """Central differences ``(dF/dy, dF/dydot)`` of a DAE system's residual at ``(y, ydot)``."""
    n = sys.size
    Jy = np.zeros((n, n))
    Jd = np.zeros((n, n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = d
        Jy[:, k] = (sys.residual(y + e, ydot) - sys.residual(y - e, ydot)) / (2 * d)
        Jd[:, k] = (sys.residual(y, ydot + e) - sys.residual(y, ydot - e)) / (2 * d)
    return Jy, Jd


#: The reference CHA equilibrium (appendix parameters, l* = 0.5) on Fourier(201).
CHA_REF = json.loads((Path(__file__).parent / "reference"
                      / "cha_trillium_equilibrium.json").read_text())


def folded_nodes(N=160, noise=0.0):
    """The reference CHA equilibrium at ``N`` nodes, as a flow's last state would be.

    Not quite at equal spacing (``N`` of ``N + 1`` equispaced nodes); ``noise`` adds a
    normal bump ``noise cos(5 s)``.
    """
    ref = CHA_REF
    c = Curve(ref["kappa"], ref["L"], Fourier(ref["N"]), ref["theta0"], tuple(ref["origin"]))
    x, y = c.on_grid(Fourier(N + 1)).positions()
    x, y = x[:N], y[:N]
    if noise:
        nx, ny = c.on_grid(Fourier(N + 1)).normal()
        bump = noise * np.cos(5 * np.arange(N) * 2 * np.pi / N)
        x, y = x + bump * nx[:N], y + bump * ny[:N]
    return x, y


_TEST_ID = re.compile(r"(tests/[\w/]+\.py)::(\w+)")


def undefined_tests(page):
    """The ``tests/...py::name`` ids a docs page names, and those not defined in their file."""
    root = Path(__file__).resolve().parent.parent
    ids = set(_TEST_ID.findall(page.read_text()))
    missing = []
    for file, name in sorted(ids):
        path = root / file
        if not path.is_file() or not re.search(rf"^def {name}\(", path.read_text(), re.M):
            missing.append(f"{file}::{name}")
    return ids, missing
