"""Curve-level two-point energy: derivative, rigid invariance, near-contact separation."""

import numpy as np
import pytest

from qsa import Curve, Fourier, geometry
from qsa.energies import Adhesion, AdhesionKernel
from qsa.energies.adhesion import adhesion_fields
from tests.helpers import inner, random_curve


@pytest.mark.parametrize("l_star", [0.5, 0.15])
def test_velocity_is_energy_derivative(l_star):
    """Moving positions by V n changes the energy at the rate int (A.n + kappa B) V dsigma."""
    grid = Fourier(201)
    c = random_curve(1, grid)
    E = Adhesion(A0=10.0, l_star=l_star, a=1.0)
    x, y = c.positions()
    n = c.normal()
    V = np.cos(2 * np.pi * grid.s) + 0.5 * np.sin(6 * np.pi * grid.s + 0.4)
    dt = 1e-5

    def energy_after(t):
        return E.energy(Curve.from_positions(x + t * V * n[0], y + t * V * n[1], grid))

    num = (energy_after(dt) - energy_after(-dt)) / (2 * dt)
    ana = inner(c, E.extrinsic_gradient(c)[: c.N], V)
    assert num == pytest.approx(ana, rel=1e-6)


def test_intrinsic_gradient_is_directional_derivative():
    """d/dd E(U + d U1) = <grad_I E, U1> for U1 tangent to the closed manifold.

    U1 is a random smooth intrinsic perturbation with its span-Psi part removed
    (the intrinsic gradient is defined modulo ker M-dagger = span Psi);
    positions come from integrating (kappa, g) (measured relative error 7e-10
    at N = 321, 2e-7 at N = 161).
    """
    c = random_curve(7, Fourier(321))
    E = Adhesion(A0=10.0, l_star=0.3, a=1.0)
    rng = np.random.default_rng(0)
    s = c.grid.s
    U1 = np.concatenate([
        sum(rng.normal() * np.cos(2 * np.pi * k * s + rng.uniform(0, 6)) for k in range(1, 5)),
        0.3 * sum(rng.normal() * np.cos(2 * np.pi * k * s + rng.uniform(0, 6)) for k in range(4)),
    ])
    Psi = geometry.constraint_gradients(c)
    G = np.array([[inner(c, p, q) for q in Psi] for p in Psi])
    U1 = U1 - np.linalg.solve(G, [inner(c, p, U1) for p in Psi]) @ Psi
    d = 1e-5
    num = (E.energy(c.with_U(c.U + d * U1)) - E.energy(c.with_U(c.U - d * U1))) / (2 * d)
    ana = inner(c, E.gradient(c), U1)
    assert abs(ana) > 0.1
    assert num == pytest.approx(ana, rel=1e-7)


def test_tangential_motion_does_not_change_the_energy():
    """Velocity V n + T tau: dE/dt = <A.n + kappa B, V>; T contributes only quadrature error."""
    c = random_curve(8, Fourier(321))
    E = Adhesion(A0=10.0, l_star=0.3, a=1.0)
    x, y = c.positions()
    tau, n = c.tangent(), c.normal()
    s = c.grid.s
    V = np.cos(2 * np.pi * s) + 0.3
    T = 5 * np.sin(4 * np.pi * s + 0.2)

    def energy_after(t):
        return E.energy(Curve.from_positions(x + t * (V * n[0] + T * tau[0]),
                                             y + t * (V * n[1] + T * tau[1]), c.grid))

    dt = 1e-5
    num = (energy_after(dt) - energy_after(-dt)) / (2 * dt)
    ana = inner(c, E.extrinsic_gradient(c)[: c.N], V)
    assert num == pytest.approx(ana, rel=1e-7)


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_rigid_invariance_identities(seed):
    """The extrinsic gradient is orthogonal to ker M; grad_s B = A.tau (Conventions, section 6).

    Both hold to quadrature accuracy, spectral once the grid resolves l_star
    (measured: 1e-2, 1e-4, 3e-8 at N = 81, 161, 321 for l_star = 0.3).
    """
    c = random_curve(seed, Fourier(321))
    E = Adhesion(A0=10.0, l_star=0.3, a=1.0)
    e = E.extrinsic_gradient(c)
    scale = np.sqrt(inner(c, e, e))
    for r in geometry.rigid_motions(c):
        assert abs(inner(c, e, r)) < 1e-6 * scale * np.sqrt(inner(c, r, r))
    B, force = E.fields(c)
    tau = c.tangent()
    assert np.abs(c.grad_s(B) - (force[:, 0] * tau[0] + force[:, 1] * tau[1])).max() \
        < 1e-3 * np.abs(force).max()


def test_intrinsic_gradient_maps_to_extrinsic():
    """M-dagger grad_I E = (A.n + kappa B, 0) (e:Adh-In_grad); off span Psi it is the
    least-squares solution of that equation (the exact gradient of E(U) with the base
    point fixed differs from it by closure gradients Psi_j only)."""
    c = random_curve(5, Fourier(321))
    E = Adhesion(A0=10.0, l_star=0.5)
    gI = E.gradient(c)
    e = E.extrinsic_gradient(c)
    Md = geometry.M_adjoint(c)
    assert np.abs(Md @ gI - e).max() < 1e-6 * np.abs(e).max()
    Psi = geometry.constraint_gradients(c)
    G = np.array([[inner(c, p, q) for q in Psi] for p in Psi])
    off = gI - np.linalg.solve(G, [inner(c, p, gI) for p in Psi]) @ Psi
    w = np.sqrt(np.concatenate([c.dsigma, c.dsigma]))
    y, *_ = np.linalg.lstsq(w[:, None] * Md / w[None, :], w * e, rcond=1e-10)
    assert np.abs(off - y / w).max() < 1e-6 * np.abs(off).max()


@pytest.mark.parametrize("a", [1.0, 0.5, 1.5])
def test_parallel_strands_separation(a):
    """Two long parallel strands: the normal force vanishes at l* sqrt(a^2 + 1/2)."""
    l_star = 0.01
    kernel = AdhesionKernel(40.0, l_star, a)
    h = l_star / 40
    u = np.arange(-15 * l_star, 15 * l_star, h)

    def normal_force(sep):
        x = np.concatenate([u, u])
        y = np.concatenate([np.zeros_like(u), np.full_like(u, sep)])
        _, force = adhesion_fields(kernel, x, y, h)
        mid = u.size // 2
        return force[mid, 1]  # on the lower strand, toward the upper one

    from scipy.optimize import brentq

    sep = brentq(normal_force, 0.5 * l_star, 3 * l_star, xtol=1e-12)
    assert sep == pytest.approx(l_star * np.sqrt(a**2 + 0.5), rel=1e-3)


@pytest.mark.parametrize("kw", [dict(A0=-1, l_star=0.1), dict(A0=1, l_star=0.0),
                                dict(A0=1, l_star=0.1, method="fast")])
def test_bad_parameters(kw):
    with pytest.raises(ValueError):
        Adhesion(**kw)
