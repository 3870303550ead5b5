"""Operators of an energy on the closed manifold: ``V^n``, the multipliers ``Lambda``, a scale.

A closed curve satisfies ``C(U) = 0`` (e:C1, e:C2); ``Psi_j = nabla_I C_j``
(:func:`qsa.geometry.constraint_gradients`) span ``ker M-dagger``. For an energy
``E`` these are properties of ``(E, C)`` alone, used by the Newton solver, the
spectra and the continuation alike:

``normal_velocity(energy, curve)``
    ``V^n = -[M-dagger nabla_I E]_1`` (e:L2grad); ``V^n = 0`` is the equilibrium
    equation (e:Abs-CP), since ``M-dagger`` kills exactly ``span Psi``.
``multipliers(energy, curve, constraints=None)``
    ``Lambda`` of ``nabla_I E = Lambda . Psi`` (e:Abs-CP): the projection of
    ``nabla_I E`` on ``span Psi`` in ``<f, h> = int f h dsigma``; with length or area
    constraints (:mod:`qsa.constraints`) also their multipliers ``mu_c`` in
    ``nabla_I E = Lambda . Psi + sum_c mu_c nabla_I c``.
``residual_scale(energy, curve)``
    The largest single term of ``V^n`` (or, where the terms vanish, their change under
    a small relative change of the state); ``max|V^n| / residual_scale`` is the
    relative residual every solver reports.
``residual_floor(energy, curve)``
    The round-off level of ``max|V^n|`` at this curve: no equilibrium of the discrete
    equations can be found, or recognised, below it.
"""

from __future__ import annotations

import numpy as np

from qsa.curve import Curve
from qsa.geometry import apply_laplace_s, constraint_gradients

__all__ = ["normal_velocity", "multipliers", "residual_scale", "residual_floor"]

_EPS = np.finfo(float).eps


def normal_velocity(energy, curve: Curve) -> np.ndarray:
    """``V^n = -[M-dagger nabla_I E]_1`` of ``energy`` at ``curve`` (e:L2grad), shape (N,).

    Equal to ``energy.normal_velocity(curve)``; for a sum of energies that is the
    sum's fast path (one Laplace-Beltrami application for all the summands that
    use the generic formula, see :class:`~qsa.energies.EnergySum`).

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    ndarray, shape (N,)
        Outward normal velocity; ``V^n = 0`` at a constrained critical point.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import CanhamHelfrich
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> bool(np.allclose(normal_velocity(CanhamHelfrich(1.0), c), 1 / 16))  # eps kappa^3 / 2
    True
    """
    return energy.normal_velocity(curve)


#: Relative change of ``kappa`` and ``g`` whose effect on the terms of ``V^n`` bounds
#: :func:`residual_scale` from below.
SCALE_CHANGE = 1e-3


def _velocity_terms(energy, curve: Curve) -> list:
    """The terms of ``V^n`` of every gradient part (arrays) and the energies' own scales."""
    N = curve.N
    out = []
    for term in energy.terms():
        own = getattr(term, "velocity_scale", None)
        if own is not None:  # an energy with its own exact V^n (e.g. a pressure)
            out.append(np.array([float(own(curve))]))
            continue
        for grad in term.gradient_parts(curve):
            mu, xi = grad[:N], curve.g * grad[N:]
            out += [apply_laplace_s(curve, mu), curve.kappa**2 * mu, curve.kappa * xi]
    return out


def residual_scale(energy, curve: Curve) -> float:
    """Largest single term of ``V^n = Delta_s mu + kappa^2 mu - kappa xi``, split by density.

    ``mu = d_kappa E`` and ``xi = g d_g E`` are taken for every part of
    ``energy.gradient_parts(curve)`` (each density of a local energy, each other
    summand whole). For ``Faceting + Perimeter`` the terms are ``alpha^2 Delta_s^2
    kappa``, ``Delta_s W'(kappa)``, ``kappa^2 mu`` and ``kappa g d_g E``.
    ``max|V^n| / residual_scale`` is the relative residual. An energy with a
    ``velocity_scale(curve)`` method (the area energies, whose ``V^n`` is a constant)
    contributes that instead.

    Where the terms vanish themselves, not only their sum, they cannot measure a
    residual: at a circle whose curvature sits at a zero of the well (``kappa = kstar``,
    ``W = W' = 0``: the critical circle of :class:`~qsa.energies.FunctionalizedCurvature`,
    or ``Faceting + Perimeter(beta, 2 pi / kstar)``) every term is 0 up to rounding. The
    scale is therefore never below the largest change of a term when ``kappa`` and ``g``
    grow by the relative amount ``SCALE_CHANGE = 1e-3`` (the size of the linearization
    of the terms along that change). Elsewhere the terms are larger than that change
    (a term of homogeneity ``p`` in ``(kappa, g)`` changes by about ``p 10^-3`` of itself),
    and the scale is the largest term.

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    float
        Positive (1.0 if every term and every change vanishes).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> round(residual_scale(Faceting(0.1, 5.0), c), 10)  # kappa^2 mu = W'(1) = 6
    6.0

    At ``kappa = kstar = 5`` the change of ``kappa^2 W'(kappa)`` sets the scale,
    ``k^2 W'(k)`` at ``k = 5 (1 + 10^-3)``, about ``10^-3 kstar^3 W''(kstar) kstar``:

    >>> c = Curve.circle(0.2, Fourier(33))
    >>> E = Faceting(0.1, 5.0) + Perimeter(5.0, 2 * np.pi * 0.2)
    >>> k = 5.0 * 1.001
    >>> bool(np.isclose(residual_scale(E, c), k**2 * k * (k - 5) * (2 * k - 5) / 2))
    True
    """
    terms = _velocity_terms(energy, curve)
    f = 1.0 + SCALE_CHANGE
    moved = _velocity_terms(energy, curve.with_kappa(curve.kappa * f).with_g(curve.g * f))
    scale = max(float(np.max(np.abs(t))) for t in terms)
    change = max(float(np.max(np.abs(t1 - t))) for t, t1 in zip(terms, moved, strict=True))
    scale = max(scale, change)
    return scale if scale > 0 else 1.0


def residual_floor(energy, curve: Curve, probes=2, seed=0) -> float:
    """Round-off level of ``max|V^n|``: its change when ``kappa, g`` move by one rounding unit.

    ``V^n`` is a differential operator of order 4 (faceting) in ``kappa``: the rounding
    of the stored curvature alone changes it by about ``eps |kappa|`` times its
    highest-order coefficients, which grow like ``N^4``. An equilibrium computed or
    checked in floating point has ``max|V^n|`` of this size at best; a curve with
    ``max|V^n| <= 100 residual_floor`` is an equilibrium to working precision.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    probes : int
        Random relative perturbations ``(1 + eps r)``, ``r = +-1``, of ``kappa`` and ``g``.
    seed : int

    Returns
    -------
    float
        ``max`` over the probes of ``max|V^n(perturbed) - V^n|``.

    Examples
    --------
    >>> from qsa import Curve, FiniteDifference
    >>> from qsa.energies import Faceting
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(1000))
    >>> floor = residual_floor(Faceting(0.1, 5.0), c)
    >>> bool(0 < floor < 1e-3 * residual_scale(Faceting(0.1, 5.0), c))
    True
    """
    rng = np.random.default_rng(seed)
    V0 = energy.normal_velocity(curve)
    worst = 0.0
    for _ in range(probes):
        k = curve.kappa * (1 + _EPS * rng.choice([-1.0, 1.0], size=curve.N))
        g = curve.g * (1 + _EPS * rng.choice([-1.0, 1.0], size=curve.N))
        V1 = energy.normal_velocity(curve.with_kappa(k).with_g(g))
        worst = max(worst, float(np.max(np.abs(V1 - V0))))
    return worst


def multipliers(energy, curve: Curve, gradient=None, constraints=None) -> np.ndarray:
    """Lagrange multipliers of ``nabla_I E = Lambda.Psi + sum_c mu_c nabla_I c`` (e:Abs-CP).

    The least-squares projection of ``nabla_I E`` onto ``span Psi`` (and the gradients of
    the extra constraints) in ``<f, h> = int f h dsigma``: ``G Lambda = b`` with the Gram
    matrix ``G_ij = <Psi_i, Psi_j>`` and ``b_i = <Psi_i, nabla_I E>``, solved by least
    squares (``rcond = 1e-12``) so that a degenerate Gram matrix is handled.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    gradient : ndarray, shape (2N,), optional
        ``nabla_I E`` in ``<f, h> = int f h dsigma`` if already computed.
    constraints : sequence of qsa.constraints.Constraint, optional
        Length / area constraints whose multipliers ``mu_c`` are appended.

    Returns
    -------
    ndarray, shape (3 + m,)
        ``(Lambda_1, Lambda_2, Lambda_3, mu_1, ..., mu_m)``; on an equilibrium
        ``nu1 = -Lambda_3``; ``mu_A`` is the pressure and ``-mu_L`` the line tension.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> c = Curve.circle(1.0, Fourier(33))  # an equilibrium: beta (L - L*) = W'(1) - W(1) = 2
    >>> E = Faceting(0.1, 5.0) + Perimeter(5.0, 2 * np.pi - 0.4)
    >>> (np.round(multipliers(E, c), 8) + 0.0).tolist()  # (0, 0, W'(1/R))
    [0.0, 0.0, 6.0]
    """
    Psi = constraint_gradients(curve)
    if constraints:
        Psi = np.vstack([Psi] + [con.gradient(curve)[None, :] for con in constraints])
    grad = energy.gradient(curve) if gradient is None else gradient
    w = np.concatenate([curve.dsigma, curve.dsigma])
    G = (Psi * w) @ Psi.T
    b = (Psi * w) @ grad
    return np.linalg.lstsq(G, b, rcond=1e-12)[0]
