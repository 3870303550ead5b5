"""The paper's DAE curve flows: residuals and analytic sparse Jacobians.

Three models implement the :class:`~qsa.flows.base.FlowModel` contract:

``CHA(eps, beta, rho, A0, l_star, a)``
    Canham-Helfrich + length penalty + adhesion-repulsion (e:CHA-Energy,
    e:CHA-GF), the system of the appendix "Discussion of Numerical Scheme":
    per node ``(x, y, kappa, kss, V)`` plus the length ``L``, ``5N + 1``
    equations.
``FacetingFlow(alpha, kstar, beta, L_star, well=None)``
    The faceting flow (e:Facet-NV) with auxiliary unknowns
    ``mu = -alpha^2 Delta_s kappa + W'(kappa)`` and ``mss = Delta_s mu`` so that
    every row has a compact stencil: per node ``(x, y, kappa, mu, mss, V)``
    plus ``L``, ``6N + 1`` equations, O(N) Jacobian nonzeros.
``SecondOrderFlow(energy)``
    The gradient flow of any local energy (e:LIE: ``SecondOrderEnergy``,
    ``FunctionalizedCurvature``, ``Faceting`` ...) plus ``Perimeter`` terms, with the
    same unknowns as ``FacetingFlow``; ``mu`` and ``g d_g E`` are the energy's own exact
    discrete gradient at ``g = L`` and the Jacobian comes from its exact Hessian
    (:mod:`qsa.flows.models.second_order`).

All share the geometric rows (scaled arc length, ap:scaledAL, ``g = L``;
``h = 1/N``; ``D1`` the centred difference, ``D2`` the compact second
difference, indices mod N; ``t_j = D1 X_j``, ``t^- = (t_y, -t_x)`` the tangent
rotated by ``-pi/2``, i.e. along the OUTWARD normal):

* normal motion      ``Xdot_j . t^-_j - L V_j = 0``                   (N rows)
* equal chords       ``|X_{j+1} - X_j|^2 / h^2 - L^2 = 0``  (ap:scaled, N rows)
* curvature          ``kappa_j - (t_x D2Y - t_y D2X)_j / L^3 = 0``     (N rows)
* model rows (auxiliary fields and the normal-velocity law)
* tangential gauge   ``h sum_j Xdot_j . t_j = 0``                      (1 row)

With ``setup(x, y, constraints=[FixedLength(), FixedArea()])`` (or ``solve_flow(...,
constraints=...)``) the flow keeps the length and/or the polygon area: one multiplier
unknown and one algebraic row each, the velocity rows corrected by ``mu_L kappa + mu_A``
(:mod:`qsa.flows.models.constrained`).

Signs follow Conventions and errata, section 3: ``V`` is the OUTWARD normal velocity and a
counter-clockwise circle of radius R has ``kappa = +1/R``.

Beyond the :class:`~qsa.flows.base.DAESystem` contract the systems offer
``unpack(y)`` (named blocks), ``curvature(y)``, ``dissipation(y)``
(``sum V^2 L/N``, the discrete ``int (V^n)^2 dsigma``),
``bound_constants()`` (``{"L0": ...}`` for CHA; ``model.setup(x, y,
**sys.bound_constants())`` rebuilds the same system, e.g. on resume),
``differential_rows``
(the rows containing ``ydot``), ``time_derivative(y)`` (the consistent ``ydot``
at a state on the constraint manifold; unconstrained flows), ``area(y)`` (the polygon
area), ``constraints`` and, for CHA, ``adhesion_fields(y)``
and ``L0``. The implementation lives in :mod:`qsa.flows.models`.

Discrete energy and dissipation: with node weights ``w = L/N`` the energy is
``E = sum_j w e_j + penalty``; along the semi-discrete flow
``dE/dt = -sum_j V_j^2 w (1 + O(h^2))`` (tested). It is not an exact discrete
gradient flow: on under-resolved curves (e.g. the appendix example at N = 50
near t = 0.2) the energy can rise by O(h^2) amounts.

Notes
-----
NOTE: the appendix writes the normal motion with the tangent rotated by
``+pi/2`` (the inward normal) and ``kappa = -(1/L^3) gamma_ss . gamma_s^perp``;
with outward ``V`` and ``kappa(circle) = +1/R`` both change sign (Conventions and errata,
section 3). NOTE: the appendix's velocity ``eps (kss - kappa^3)`` is wrong; the
gradient flow of e:CHA-Energy has ``eps (kss + kappa^3 / 2)`` (Conventions and errata,
section 3), verified here by the discrete energy-dissipation test.
"""

from qsa.flows.models import (
    CHA,
    CHASystem,
    CurveDAE,
    FacetingFlow,
    FacetingSystem,
    SecondOrderFlow,
    SecondOrderSystem,
    equalize_chords,
    flow_model,
    self_intersections,
)

__all__ = ["CHA", "FacetingFlow", "SecondOrderFlow", "CurveDAE", "CHASystem", "FacetingSystem",
           "SecondOrderSystem", "equalize_chords", "flow_model", "self_intersections"]
