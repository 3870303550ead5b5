r"""Evaluation of the front ODE's reduced system: one interface, a numpy and a numba backend.

A backend evaluates, at front positions ``p`` (and, for a variable length, ``L``), the
saddle-point system of the reduced flow (:mod:`qsa.reduction.ode`) ::

    [ G   A^T ] [ p' ]   [ -dE/dp ]
    [ A   0   ] [ mu ] = [    0   ],    A = [ dC/dp ; 1^T / sqrt(2N) ],

with its ingredients, and solves it. The contract (both backends):

``evaluate(p, cutoff, L, correction) -> FrontEvaluation``
    Everything, named. ``L`` is ``None`` at the fixed length, else the current length
    (then an unknown: ``(p', L')``); ``correction`` selects the Newton-corrected force
    (``True``, :mod:`qsa.reduction.correction`) or the manifold of quasi-steady
    profiles (``"profile"``, ``"profile-lag"``, :mod:`qsa.reduction.quasisteady`;
    numpy only).
``velocity(p, cutoff, L, correction) -> ndarray``
    The solution of the saddle-point system only (``p'`` [, ``L'``], then the four
    multipliers): the integrator's hot path.
``name``
    ``"numpy"`` or ``"numba"``.

A singular saddle-point matrix (degenerate constraints, e.g. a symmetric lens) is
solved by least squares; a singular rigid-motion projection raises
``numpy.linalg.LinAlgError`` (a wild trial stage of the integrator, which rejects it).

:class:`NumpyBackend` is the reference (spectral cumulative integrals,
:mod:`qsa.reduction.manifold`). :class:`NumbaBackend` runs one compiled kernel per
evaluation (:mod:`qsa.reduction._kernels`; the optional ``numba``, quartic well only);
the two agree to round-off amplified by the solves (tested).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.reduction.correction import newton_correction
from qsa.reduction.manifold import (
    closure,
    energy_gradient,
    length_derivatives,
    normal_velocities,
    splice_fields,
)
from qsa.reduction.quasisteady import profile_normal_velocities, quasisteady_profile

__all__ = ["FrontEvaluation", "NumpyBackend", "NumbaBackend", "select_backend"]


@dataclass(frozen=True, eq=False)
class FrontEvaluation:
    """The reduced system at one state (``n = 2N``, or ``2N + 1`` with a variable length).

    Attributes
    ----------
    velocity : ndarray, shape (n,)
        ``p'`` (and ``L'`` last with a variable length).
    multipliers : ndarray, shape (4,)
        ``mu`` of the closure constraints (three) and of the base point.
    normal_velocities : ndarray, shape (M, 2N)
        ``phi_j^perp`` on the quadrature nodes; on the profile manifold with a
        variable length also ``phi_L^perp`` (shape (M, 2N + 1)): there lengthening
        the curve at fixed ``p`` changes its profile everywhere.
    weights : ndarray, shape (M,)
        Quadrature weights ``dsigma``.
    metric : ndarray, shape (n, n)
        ``G`` (on the splice manifold the length row and column are zero: lengthening
        moves no point of the curve and costs no dissipation; on the profile manifold
        they are those of ``phi_L^perp``).
    force : ndarray, shape (n,)
        ``dE/dp`` (Newton-corrected if asked; and ``dE/dL + beta (L - L*)``).
    closure : ndarray, shape (3,)
        ``C(p)``.
    closure_jacobian : ndarray, shape (3, 2N)
        ``dC/dp``.
    matrix : ndarray, shape (n + 4, n + 4)
        The saddle-point matrix ``K``.
    rhs : ndarray, shape (n + 4,)
        Its right-hand side ``(-force, 0)``.
    """

    velocity: np.ndarray
    multipliers: np.ndarray
    normal_velocities: np.ndarray
    weights: np.ndarray
    metric: np.ndarray
    force: np.ndarray
    closure: np.ndarray
    closure_jacobian: np.ndarray
    matrix: np.ndarray
    rhs: np.ndarray


def _solve_saddle(K, rhs):
    try:
        return np.linalg.solve(K, rhs)
    except np.linalg.LinAlgError:  # degenerate constraints (e.g. a symmetric lens)
        return np.linalg.lstsq(K, rhs, rcond=1e-12)[0]


@dataclass(frozen=True, eq=False)
class NumpyBackend:
    """The reference evaluation with numpy (any well).

    Parameters
    ----------
    front : Heteroclinic
    length : float
        The fixed length (used when ``L`` is None).
    quadrature : PeriodicQuadrature
    band : (ndarray, ndarray)
        ``folded_band(M, D2_STENCIL)`` of the Newton correction.
    beta : float or None
        Perimeter penalty (None: fixed length).
    L_star : float
    """

    front: object
    length: float
    quadrature: object
    band: tuple
    beta: float | None = None
    L_star: float | None = None
    name = "numpy"

    def fields(self, p, cutoff, L=None):
        """:func:`qsa.reduction.manifold.splice_fields` on the quadrature (``L`` default: fixed)."""
        L = self.length if L is None else float(L)
        return splice_fields(self.front, p, L, cutoff, self.quadrature,
                             variable=self.beta is not None)

    def correct(self, fields):
        """``(delta, R)`` of :func:`~qsa.reduction.correction.newton_correction`."""
        return newton_correction(fields.psi, fields.d2psi, fields.dpsi_dp, fields.length,
                                 self.front.alpha, self.front.well, self.band)

    def profile(self, fields, lag=False, length=False):
        """:func:`~qsa.reduction.quasisteady.quasisteady_profile` of the splice ``fields``."""
        qs = quasisteady_profile(fields, self.front.alpha, self.front.well, self.band,
                                 self.quadrature, lag=lag, length=length)
        if not qs.converged:
            raise np.linalg.LinAlgError("the quasi-steady profile did not converge")
        return qs

    def evaluate(self, p, cutoff, L=None, correction=False):
        """:class:`FrontEvaluation` at ``p`` (see the module docstring)."""
        f = self.fields(p, cutoff, L)
        front = self.front
        R, lag = None, None
        on_profile = correction in ("profile", "profile-lag")
        if on_profile:
            qs = self.profile(f, lag=correction == "profile-lag", length=L is not None)
            f, R, lag = qs.fields, qs.residual, qs.lag
            # with a variable length the profile moves the curve as L changes: phi_L
            phi = profile_normal_velocities(f, self.quadrature)
        else:
            if correction:
                R = self.correct(f)[1]
            phi = normal_velocities(f, self.quadrature)
        G = phi.T @ (f.weights[:, None] * phi)
        dE = energy_gradient(f, front.alpha, front.well, R)
        C, J = closure(f)
        n = p.size
        A = np.vstack([J, np.ones((1, n)) / np.sqrt(n)])
        if L is not None:
            dEL, dCL = length_derivatives(f, front.alpha, front.well)
            dEL += self.beta * (L - self.L_star)
            if not on_profile:  # the splice's lengthening moves no point of the curve
                G = np.pad(G, ((0, 1), (0, 1)))
            dE = np.append(dE, dEL)
            A = np.column_stack([A, np.append(dCL, 0.0)])
            n += 1
        K = np.zeros((n + 4, n + 4))
        K[:n, :n], K[:n, n:], K[n:, :n] = G, A.T, A
        rhs = np.zeros(n + 4)
        rhs[:n] = -dE
        sol = _solve_saddle(K, rhs)
        if lag is not None:
            # the lag of the fast profile behind the fronts: G p' - C p'' = -dE/dp, with
            # p'' the acceleration of the quasi-steady flow (a directional difference)
            v = sol[:n]
            vmax = float(np.max(np.abs(v)))
            if vmax > 0:
                eps = 1e-4 * self.front.width / vmax
                vp, vm = (self._shifted(p, L, d * v, cutoff) for d in (eps, -eps))
                dE = dE - lag @ ((vp - vm) / (2 * eps))
                rhs[:n] = -dE
                sol = _solve_saddle(K, rhs)
        return FrontEvaluation(sol[:n], sol[n:], phi, f.weights, G, dE, C, J, K, rhs)

    def _shifted(self, p, L, dy, cutoff):
        """The ``"profile"`` velocity at the state ``(p [, L]) + dy``."""
        if L is None:
            return self.evaluate(p + dy, cutoff, None, "profile").velocity
        return self.evaluate(p + dy[:-1], cutoff, L + dy[-1], "profile").velocity

    def velocity(self, p, cutoff, L=None, correction=False):
        """The saddle-point solution ``(p' [, L'], mu)``, shape (n + 4,)."""
        e = self.evaluate(p, cutoff, L, correction)
        return np.concatenate([e.velocity, e.multipliers])


@dataclass(frozen=True, eq=False)
class NumbaBackend:
    """The compiled evaluation (:mod:`qsa.reduction._kernels`; quartic well only).

    Parameters
    ----------
    reference : NumpyBackend
        Same parameters; takes over where a solve of the Newton correction is singular
        (its fallbacks).
    """

    reference: NumpyBackend
    _args: tuple = field(init=False, repr=False)
    _rhs: object = field(init=False, repr=False)
    _velocity: object = field(init=False, repr=False)
    name = "numba"

    def __post_init__(self):
        from qsa.reduction import _kernels  # optional dependency (ImportError without numba)

        ref = self.reference
        front = ref.front
        if not front.closed_form:
            raise ValueError("backend='numba' supports the quartic well only")
        perm, band = ref.band
        args = (float(front.kstar), float(front.rates[0]), float(front.alpha**2),
                int(ref.quadrature.M), _kernels.end_weights(_kernels.cell_weights(8)))
        object.__setattr__(self, "_args", (args, _kernels.band_rows(perm, band),
                                           np.ascontiguousarray(perm, dtype=np.int64)))
        object.__setattr__(self, "_rhs", _kernels.front_rhs)
        object.__setattr__(self, "_velocity", _kernels.front_velocity)

    def _call(self, fn, p, cutoff, L, correction):
        ref = self.reference
        (k, lam, a2, M, wq), band, perm = self._args
        Lv = float(ref.length if L is None else L)
        l1, l2 = cutoff
        beta = 0.0 if ref.beta is None else float(ref.beta)
        return fn(np.ascontiguousarray(p, dtype=float), Lv, float(l1), float(l2), k, lam, a2,
                  M, wq, bool(correction), band, perm, L is not None, beta, float(ref.L_star))

    def evaluate(self, p, cutoff, L=None, correction=False):
        """:class:`FrontEvaluation` at ``p`` (see the module docstring)."""
        sol, status, phi, G, dE, C, J, K, rhs = self._call(self._rhs, p, cutoff, L, correction)
        if status == 3:  # a singular solve in the Newton correction: the numpy fallbacks
            return self.reference.evaluate(p, cutoff, L, correction)
        if status == 2:
            raise np.linalg.LinAlgError("Singular matrix")
        if status == 1:  # degenerate constraints: as the numpy path
            sol = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
        n = p.size + (L is not None)
        Lv = self.reference.length if L is None else float(L)
        w = Lv * self.reference.quadrature.weights
        return FrontEvaluation(sol[:n], sol[n:], phi.T.copy(), w, G, dE, C, J, K, rhs)

    def velocity(self, p, cutoff, L=None, correction=False):
        """The saddle-point solution ``(p' [, L'], mu)``, shape (n + 4,)."""
        sol, status = self._call(self._velocity, p, cutoff, L, correction)
        if status == 0:
            return sol
        if status == 1:  # degenerate constraints: as the numpy path
            _, _, _, _, _, _, _, K, rhs = self._call(self._rhs, p, cutoff, L, correction)
            return np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
        if status == 2:  # (a wild trial stage of the integrator)
            raise np.linalg.LinAlgError("Singular matrix")
        return self.reference.velocity(p, cutoff, L, correction)


def select_backend(name, reference):
    """The backend ``name`` ("auto", "numpy", "numba") for the parameters of ``reference``.

    ``"auto"``: numba when importable and the well is the quartic, else numpy.

    Raises
    ------
    ValueError
        An unknown name, or ``"numba"`` without numba or with another well.
    """
    if name not in ("auto", "numpy", "numba"):
        raise ValueError(f"backend must be 'auto', 'numpy' or 'numba', got {name!r}")
    if name == "numpy":
        return reference
    try:
        return NumbaBackend(reference)
    except ImportError as exc:
        if name == "numba":
            raise ValueError("backend='numba' needs numba (pip install numba, or the "
                             "'fast' extra: pip install qsa[fast])") from exc
    except ValueError:
        if name == "numba":
            raise
    return reference
