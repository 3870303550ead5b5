"""Energy Hessian and the Lagrangian Hessian ``L_Lambda = nabla^2 E - Lambda . nabla^2 C``.

Constrained critical points satisfy ``nabla_I E = Lambda . Psi`` (e:Abs-CP) with
``Psi_j = nabla_I C_j`` spanning ``ker M-dagger``. The second variation of ``E`` on
the closed manifold ``C(U) = 0`` is the quadratic form of ::

    L_Lambda = nabla_I^2 E - sum_j Lambda_j nabla_I^2 C_j,

not of ``nabla_I^2 E`` alone (e:cF-Hessian is the energy part; the constraint
Hessians e:cC-Hessian, e:cC-Hessian3 are taken from :mod:`qsa.geometry`, which
implements their corrected form).

# NOTE: the paper linearizes with ``nabla^2 E`` (e:FOE-Lin); Conventions and errata, section 4 shows
# that this is only right when ``Lambda = 0`` and that the correct operator is
# ``L_Lambda``. Both are available here and in :mod:`qsa.spectra.linearization`.

``Lambda`` is the least-squares projection of ``nabla_I E`` on ``span Psi`` in
``<f, h> = int f h dsigma`` (:func:`qsa.equilibria.multipliers`); the projection
residual ``|nabla_I E - Lambda . Psi|`` measures how far the curve is from a
constrained critical point and is reported with every Hessian.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.closure import closure_hessian
from qsa.constraints import bind_constraints, project_velocity
from qsa.curve import Curve
from qsa.energies.base import Energy, add_matrices
from qsa.energies.constrained import (
    multipliers,
    normal_velocity,
    residual_floor,
    residual_scale,
)
from qsa.geometry import constraint_gradients
from qsa.linalg import ReducedHessian

__all__ = ["hessian", "lagrange_hessian", "LagrangeHessian", "inner_norm", "check_input",
           "DENSE_CONSTRAINT_LIMIT"]

#: Largest N for which the constraint Hessians of ``C_1, C_2`` (O(N^2) memory) are
#: assembled densely on finite-difference grids when the energy Hessian is not itself
#: factored; above it (or with a factored energy Hessian) they are factored
#: (:func:`qsa.closure.closure_hessian`).
DENSE_CONSTRAINT_LIMIT = 1200


def check_input(energy, curve):
    """Raise ``ValueError`` naming the argument unless ``energy``/``curve`` are usable.

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    None

    Raises
    ------
    ValueError
        ``energy`` not a qsa Energy or ``curve`` not a Curve.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> check_input("not an energy", Curve.circle(1.0, Fourier(9)))
    Traceback (most recent call last):
    ...
    ValueError: energy must be a qsa Energy (e.g. Faceting(...) + Perimeter(...)), got str
    """
    if not isinstance(energy, Energy):
        raise ValueError(f"energy must be a qsa Energy (e.g. Faceting(...) + Perimeter(...)), "
                         f"got {type(energy).__name__}")
    if not isinstance(curve, Curve):
        raise ValueError(f"curve must be a qsa Curve, got {type(curve).__name__}")


def inner_norm(curve: Curve, f) -> float:
    """``sqrt(<f, f>)`` for a nodal (N,) or stacked (2N,) vector, ``<f, h> = int f h dsigma``.

    Parameters
    ----------
    curve : Curve
    f : ndarray, shape (N,) or (2N,)

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> round(inner_norm(c, np.ones(17)) ** 2 / np.pi, 12)  # int 1 dsigma = 2 pi
    2.0
    >>> round(inner_norm(c, np.ones(34)) ** 2 / np.pi, 12)
    4.0
    """
    f = np.asarray(f, dtype=float)
    w = curve.dsigma
    if f.shape[0] == 2 * curve.N:
        w = np.concatenate([w, w])
    return float(np.sqrt(np.sum(w * f * f)))


def hessian(energy, curve: Curve):
    """``nabla_I^2 E`` with respect to ``<f, h> = int f h dsigma`` (e:cF-Hessian).

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    matrix, shape (2N, 2N)
        ``energy.hessian(curve)``: dense for Fourier grids, sparse or
        :class:`~qsa.linalg.SparsePlusLowRank` (perimeter penalty) for finite
        differences. dsigma-self-adjoint.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> H = hessian(eq.energy, eq.curve)
    >>> A = np.concatenate([eq.curve.dsigma] * 2)[:, None] * H  # W H is symmetric
    >>> H.shape, bool(np.allclose(A, A.T))
    ((34, 34), True)
    """
    check_input(energy, curve)
    return energy.hessian(curve)


@dataclass(frozen=True, eq=False)
class LagrangeHessian:
    """The Lagrangian Hessian at a curve and how close the curve is to equilibrium.

    Attributes
    ----------
    matrix : matrix, shape (2N, 2N)
        ``L_Lambda = nabla_I^2 E - Lambda . nabla_I^2 C`` (dsigma-self-adjoint); same
        matrix type as the energy Hessian, except that the ``C_1, C_2`` Hessians, when
        included, make it dense (small grids) or a :class:`~qsa.linalg.ReducedHessian`.
    energy_hessian : matrix, shape (2N, 2N)
        ``nabla_I^2 E``.
    multipliers : ndarray, shape (3,)
        ``Lambda``, the projection coefficients of ``nabla_I E`` on ``Psi``.
    projection_residual : float
        ``|nabla_I E - Lambda . Psi|`` in the ``<.,.>`` norm: zero exactly at a
        constrained critical point.
    relative_projection_residual : float
        ``projection_residual / max(|nabla_I E|, |Lambda . Psi|)`` (0 if both vanish).
    residual : float
        ``max |V^n|`` (the normal velocity; zero at an equilibrium).
    relative_residual : float
        ``residual`` divided by the largest single term of ``V^n``
        (:func:`qsa.energies.residual_scale`): the scale-free distance from equilibrium.
    constraints_included : tuple of bool, shape (3,)
        Which ``Lambda_j nabla^2 C_j`` terms are in ``matrix``.
    message : str
    residual_floor : float
        The round-off level of ``max|V^n|`` at this curve
        (:func:`qsa.energies.residual_floor`).
    constraints : tuple of Constraint
        Length / area constraints (:mod:`qsa.constraints`) whose multiplier terms
        ``- mu_c nabla^2 c`` are in ``matrix``; then ``residual`` is ``max|V^n + mu . n|``
        with the constrained flow's multipliers (:func:`qsa.constraints.flow_multipliers`)
        and the projection is onto ``span(Psi, nabla_I c)``.
    constraint_multipliers : ndarray, shape (m,)
        ``mu_c`` of ``nabla_I E = Lambda . Psi + sum_c mu_c nabla_I c`` (projection).

    Parameters
    ----------
    Constructed by :func:`lagrange_hessian`; the fields are the attributes above.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> LH = lagrange_hessian(eq.energy, eq.curve)
    >>> (np.round(LH.multipliers, 8) + 0.0).tolist(), bool(LH.relative_projection_residual < 1e-12)
    ([0.0, 0.0, 6.0], True)
    """

    matrix: object
    energy_hessian: object
    multipliers: np.ndarray
    projection_residual: float
    relative_projection_residual: float
    residual: float
    relative_residual: float
    constraints_included: tuple
    message: str = ""
    residual_floor: float = 0.0
    constraints: tuple = ()
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def is_equilibrium(self, tol=1e-6) -> bool:
        """``relative_residual <= tol``, or ``max|V^n|`` within 100 times its round-off floor.

        Parameters
        ----------
        tol : float

        Returns
        -------
        bool
        """
        return bool(self.relative_residual <= tol or self.residual <= 100 * self.residual_floor)


def lagrange_hessian(energy, curve: Curve, constraints=None, *, closure="auto") -> LagrangeHessian:
    """The Lagrangian Hessian ``L_Lambda = nabla_I^2 E - sum_j Lambda_j nabla_I^2 C_j``.

    With length / area constraints, ``L = nabla_I^2 E - Lambda . nabla_I^2 C -
    sum_c mu_c nabla_I^2 c``, the multipliers from the projection of ``nabla_I E`` onto
    ``span(Psi, nabla_I c)``.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    constraints : sequence of Constraint, optional
        E.g. ``[FixedLength(), FixedArea()]`` (:mod:`qsa.constraints`). A string is
        read as ``closure`` (its former meaning).
    closure : {"auto", "all", "curvature"}
        Which closure Hessians to subtract. ``"all"``: all three.
        ``"curvature"``: only ``Lambda_3 nabla^2 C_3`` (sparse). ``"auto"`` (default):
        ``C_3`` always; ``C_1, C_2`` only when significant,
        ``|Lambda_j Psi_j| > max(|nabla_I E - Lambda . Psi|, 1e-8 |nabla_I E|)`` (else
        the term is below the accuracy of the projection itself; for the local
        energies ``Lambda_{1,2} = 0`` at equilibria, while two-point energies transmit
        a tension through the base point and have ``Lambda_{1,2} != 0``). ``C_1, C_2``
        enter through :func:`qsa.closure.closure_hessian`: dense on Fourier grids and
        on finite-difference grids up to :data:`DENSE_CONSTRAINT_LIMIT` nodes, a
        factored :class:`~qsa.linalg.ReducedHessian` (O(N) storage) beyond, or
        whenever the energy Hessian is one.

    Returns
    -------
    LagrangeHessian
        The matrix (``<.,.>``-self-adjoint), ``Lambda``, and the projection and
        equilibrium residuals.

    Notes
    -----
    ``Lambda`` is the ``<.,.>``-least-squares solution of ``nabla_I E = Lambda . Psi``
    (Conventions and errata, section 4); e:Abs-CP, e:cF-Hessian, e:cC-Hessian, e:cC-Hessian3.

    Examples
    --------
    >>> from qsa import Fourier
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.7, 0.1, grid=Fourier(33))
    >>> LH = lagrange_hessian(eq.energy, eq.curve)
    >>> bool(abs(LH.multipliers[2] - eq.multipliers[2]) < 1e-10), LH.relative_residual < 1e-12
    (True, True)
    """
    check_input(energy, curve)
    if isinstance(constraints, str):  # the former name of ``closure``
        closure, constraints = constraints, None
    if closure not in ("auto", "all", "curvature"):
        raise ValueError(f"closure (formerly constraints=) must be 'auto', 'all' or 'curvature', "
                         f"got {closure!r}")
    cons = bind_constraints(constraints, curve)
    H = energy.hessian(curve)
    grad = energy.gradient(curve)
    Lam = multipliers(energy, curve, gradient=grad, constraints=cons)
    Lam, mu = Lam[:3], Lam[3:]
    Psi = constraint_gradients(curve)
    grads = [con.gradient(curve) for con in cons]
    proj = Lam @ Psi + sum(m * gc for m, gc in zip(mu, grads, strict=True))
    res_abs = inner_norm(curve, grad - proj)
    denom = max(inner_norm(curve, grad), inner_norm(curve, proj))
    res_rel = res_abs / denom if denom > 0 else 0.0
    Vn = project_velocity(cons, curve, normal_velocity(energy, curve))
    vres = float(np.max(np.abs(Vn)))
    vrel = vres / residual_scale(energy, curve)
    vfloor = residual_floor(energy, curve)

    floor = max(res_abs, 1e-8 * inner_norm(curve, grad))
    significant = any(abs(Lam[j]) * inner_norm(curve, Psi[j]) > floor for j in range(2))
    use12 = closure == "all" or (closure == "auto" and significant)
    weights = Lam.copy() if use12 else np.array([0.0, 0.0, Lam[2]])
    # dense C_1, C_2 Hessians where the energy Hessian is a matrix anyway (small grids);
    # factored where it is factored or the grid is large
    dense = not curve.grid.sparse or (curve.N <= DENSE_CONSTRAINT_LIMIT
                                      and not isinstance(H, ReducedHessian)
                                      and use12)
    L = H
    if np.any(weights != 0.0):
        L = add_matrices(H, -closure_hessian(curve, weights, "dense" if dense else "auto"))
    for con, m in zip(cons, mu, strict=True):
        if m != 0.0:
            L = add_matrices(L, -m * con.hessian(curve))
    included = (use12, use12, True)
    msg = (f"Lambda = {np.array2string(Lam, precision=6)}; "
           + "".join(f"mu_{con.symbol} = {m:.6g}; " for con, m in zip(cons, mu, strict=True))
           + f"projection residual "
           f"{res_abs:.2e} ({res_rel:.1e} relative); max|V^n| = {vres:.2e} "
           f"({vrel:.1e} of the largest term, {vres / max(vfloor, 1e-300):.1e} times its "
           "round-off floor)")
    if not use12:
        msg += (f"; Lambda_1,2 terms omitted (|Lambda_1,2| = {np.abs(Lam[:2]).max():.1e}, "
                "below the projection's accuracy)")
    return LagrangeHessian(L, H, Lam, res_abs, res_rel, vres, vrel, included, msg, vfloor,
                           cons, mu)
