r"""The front-position ODE: quasi-steady faceting dynamics on the splice manifold.

Between coarsening events a faceting flow (e:Facet-NV) stays close to the manifold of
heteroclinic splices ``psi_N(p)`` (e:psi_N; built by
:class:`qsa.equilibria.SpliceProfile`) and only the front positions
``p = (p_1 < ... < p_2N)`` move, exponentially slowly. :class:`FrontODE` reduces the
flow to ``p' = F(p)``.

Reduced flow
------------
The flow is the gradient flow of ``E`` for the metric of its normal velocity modulo
rigid motions; pulled back to the splice manifold this is the Gram matrix ``G`` of
the normal velocities ``phi_j^perp`` of the positions, and the force is
``dE/dp_j = int R_kappa d psi_N / d p_j dsigma`` (derived in
:mod:`qsa.reduction.manifold`). The closure constraints ``C(p) = 0`` (e:C1, e:C2)
restrict ``p`` to a manifold of dimension ``2N - 3``; the base point is fixed by
``sum p_j' = 0``. The constrained gradient flow of ``E(p)`` in the metric ``G``
(equivalently the Galerkin projection of ``V^n`` on the tangent space,
``min |V^n - sum p_j' phi_j^perp|``) is the saddle-point system ::

    [ G   A^T ] [ p' ]   [ -dE/dp ]
    [ A   0   ] [ mu ] = [    0   ],    A = [ dC/dp ; 1^T / sqrt(2N) ],

``mu`` the multipliers (the first three are ``Lambda``-like), evaluated by a backend
(:mod:`qsa.reduction.backends`). ``F(p) = p'`` decreases ``E`` at the rate
``p'^T G p'`` (tested). The front positions here are the splice parameters ``p_j``;
on the profile they are the ``kstar / 2`` crossings up to the neighbours' tails
(:meth:`FrontODE.crossings` gives the crossings).

*Variable length.* With ``beta`` given, ``L`` is a further unknown and the energy
gains ``beta/2 (L - L*)^2``. Lengthening the curve at fixed ``p`` moves no point of
the curve: it costs no dissipation, but it changes ``C`` and ``E``
(:func:`qsa.reduction.manifold.length_derivatives`). So ``L'`` is tied to ``p'`` by
the closure rows and the saddle-point system gains one unknown and one row:
``dC/dL L' + dC/dp p' = 0`` and ``(dC/dL) . mu = -(dE/dL + beta (L - L*))``. At the
quasi-static length (``L' = 0``) of a stiff perimeter it reduces to the fixed-length
flow (tested). On the manifold of quasi-steady profiles (below) lengthening does move
the curve -- the profile changes everywhere with ``L`` -- and the length has its own
normal velocity, metric row and column (:mod:`qsa.reduction.quasisteady`).

*Force correction.* ``correction="newton"`` evaluates the force with the residual of
the splice corrected by one Newton step towards the slow manifold
(:mod:`qsa.reduction.correction`): the splice superposes the overlapping tails of a
closing gap linearly, while the well's nonlinearity lifts the true quasi-steady
profile there, which strengthens the attraction. Tested on the short facet: with the
correction the collision time is within 1% of the DAE's (N = 600; variable length
against beta = 5, fixed length against a stiff perimeter), without it the fixed-length
one is more than 1.5% off.

*The quasi-steady manifold.* ``correction="profile"`` replaces the splice by the
profile that solves the profile equation up to a force along the reduced tangent
space and the three closure multipliers (:mod:`qsa.reduction.quasisteady`), and
evaluates metric, closure and force on it. It contains the exact N-pulse of a
regular polygon, whose plateaus the turning multiplier lifts, so the reduction's
linearization there is the Rayleigh-Ritz approximation of the full one on the
manifold's tangent space; ``"profile-lag"`` adds the lag of the profile behind the
fronts (``G p' - C p'' = -dE/dp``), which is what is left for corners of 0.16-0.2:
the slow eigenvalues of the regular polygons with 3-8 corners and facets 0.25-0.5
agree with the full linearization's within 0.35% (the front-ODE page of the
documentation).

*Collisions and validity* are in :mod:`qsa.reduction.integrate` (:meth:`integrate`).
The measured accuracy (against the DAE flow) and cost are on the front-ODE page of the
documentation and in the output of ``benchmarks/bench_reduction.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.energies.wells import resolve_well
from qsa.equilibria import heteroclinic
from qsa.equilibria.profile import SpliceProfile
from qsa.equilibria.splice import default_cutoff
from qsa.reduction import manifold
from qsa.reduction.backends import NumpyBackend, select_backend
from qsa.reduction.correction import D2_STENCIL, folded_band
from qsa.reduction.fronts import detect_fronts
from qsa.reduction.integrate import (
    FrontODEResult,
    ODECollision,
    ODESegment,
    collision_distance,
    collision_sensitivity,
    integrate_fronts,
)
from qsa.reduction.manifold import PeriodicQuadrature, quadrature_size

__all__ = ["FrontODE", "FrontODEResult", "ODECollision", "ODESegment", "collision_distance",
           "collision_sensitivity"]


@dataclass(frozen=True)
class FrontODE:
    """The front-position ODE ``p' = F(p)`` of the faceting flow (see the module docstring).

    Parameters
    ----------
    alpha, kstar : float
        Faceting parameters (``alpha > 0``).
    length : float
        Curve length ``L`` (``= L*``; fixed).
    well : object, optional
        Double well (default the quartic).
    cutoff : (float, float), optional
        Fixed cutoff of the fronts (:class:`SpliceProfile`); default
        :func:`qsa.equilibria.default_cutoff` of the positions passed to
        :meth:`integrate` (kept fixed between collisions).
    points_per_width : float
        Quadrature resolution (nodes per front width ``1/lambda``).
    beta : float, optional
        Perimeter penalty ``beta/2 (L - L*)^2``. ``None`` (default): ``L`` is held
        at ``length`` (the ``beta -> inf`` limit). Otherwise ``L`` is a further
        unknown (state ``(p, L)``, see "Variable length" in the module docstring).
    L_star : float, optional
        Preferred length (default ``length``).
    correction : {None, "newton", "profile", "profile-lag"}
        ``"newton"``: evaluate the force ``dE/dp_j`` with the residual of the profile
        corrected by one Newton step towards the slow manifold
        (:meth:`slow_correction`) instead of the splice's own residual; one banded
        solve of size ``M`` (quadrature nodes) per evaluation. ``"profile"``: the
        reduction on the manifold of constrained quasi-steady profiles
        (:mod:`qsa.reduction.quasisteady`: metric, force and closure of the profile
        converged by Newton, 3-5 banded solves per evaluation); ``"profile-lag"``: the
        same with the lag of the profile behind moving fronts (three such
        evaluations). Both run on numpy (``backend="auto"`` picks it; ``"numba"`` is
        refused); with ``beta`` the length is an unknown of the profile too (its
        tangent in ``L``, :mod:`qsa.reduction.quasisteady`).
    backend : {"auto", "numpy", "numba"}
        Evaluation of the right-hand side (:mod:`qsa.reduction.backends`). ``"numpy"``:
        the reference (spectral cumulative integrals). ``"numba"``: one compiled kernel
        per evaluation (needs the optional ``numba``, ``pip install qsa[fast]``, and the
        quartic well); same results to round-off. ``"auto"`` (default): numba when
        importable and the well is the quartic, else numpy. :attr:`backend_used` tells
        which one runs.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import splice_polygon
    >>> eq = splice_polygon(np.radians([130, 120, 110]), [0.3, 0.4, 0.5], 0.1, kstar=5.0)
    >>> ode = FrontODE(0.1, 5.0, eq.params["L"], backend="numpy")
    >>> p = np.array(eq.params["positions"])
    >>> v = ode.velocity(p)
    >>> v.shape, bool(abs(v.sum()) < 1e-12), bool(ode.gradient(p) @ v < 0)  # E decreases
    ((6,), True, True)
    """

    alpha: float
    kstar: float
    length: float
    well: object = None
    cutoff: tuple | None = None
    points_per_width: float = 3.0
    beta: float | None = None
    L_star: float | None = None
    correction: str | None = None
    backend: str = "auto"
    front: object = field(init=False, repr=False)
    grid: object = field(init=False, repr=False)
    _quadrature: PeriodicQuadrature = field(init=False, repr=False, compare=False)
    _reference: NumpyBackend = field(init=False, repr=False, compare=False)
    _evaluator: object = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        for name in ("alpha", "kstar", "length", "points_per_width"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be positive, got {v!r}")
        well, kstar = resolve_well(self.well, self.kstar)
        front = heteroclinic(self.alpha, well, kstar)
        object.__setattr__(self, "front", front)
        quad = PeriodicQuadrature(quadrature_size(self.length, front.width,
                                                  self.points_per_width))
        object.__setattr__(self, "_quadrature", quad)
        object.__setattr__(self, "grid", quad.grid)
        if self.beta is not None and not (np.isfinite(self.beta) and self.beta >= 0):
            raise ValueError(f"beta must be non-negative, got {self.beta!r}")
        if self.L_star is None:
            object.__setattr__(self, "L_star", float(self.length))
        if self.correction not in (None, "newton", "profile", "profile-lag"):
            raise ValueError(f"correction must be None, 'newton', 'profile' or 'profile-lag', "
                             f"got {self.correction!r}")
        ref = NumpyBackend(front, self.length, quad, folded_band(quad.M, D2_STENCIL),
                           self.beta, self.L_star)
        object.__setattr__(self, "_reference", ref)
        if self.correction in ("profile", "profile-lag"):
            if self.backend == "numba":
                raise ValueError(f"backend='numba' supports correction None or 'newton'; use "
                                 f"backend='numpy' or 'auto' with correction={self.correction!r}")
            object.__setattr__(self, "_evaluator", select_backend("numpy", ref))
        else:
            object.__setattr__(self, "_evaluator", select_backend(self.backend, ref))

    @property
    def backend_used(self):
        """The backend actually evaluating the right-hand side: ``"numpy"`` or ``"numba"``."""
        return self._evaluator.name

    @property
    def evaluator(self):
        """The backend object (:mod:`qsa.reduction.backends`) evaluating the right-hand side."""
        return self._evaluator

    @property
    def sigma(self):
        """Quadrature nodes in arc length, shape (M,)."""
        return self.length * self.grid.s

    @property
    def collision_distance(self):
        """:func:`collision_distance` of the front."""
        return collision_distance(self.front)

    def _cut(self, p, cutoff, L=None):
        return cutoff or self.cutoff or default_cutoff(p, self.length if L is None else L)

    def profile(self, p, cutoff=None):
        """The :class:`SpliceProfile` at positions ``p``."""
        p = np.asarray(p, dtype=float)
        return SpliceProfile(self.front, p, self.length, self._cut(p, cutoff))

    def _check(self, p):
        p = np.asarray(p, dtype=float)
        if p.ndim != 1 or p.size < 4 or p.size % 2:
            raise ValueError(f"p must hold 2N >= 4 positions, got shape {p.shape}")
        if not np.all(np.isfinite(p)):
            raise ValueError("p contains NaN or inf")
        if np.any(np.diff(p) <= 0) or p[-1] - p[0] >= self.length:
            raise ValueError("p must increase strictly and span less than the length")
        return p

    def _check_length(self, p, L):
        if self.beta is None:
            raise ValueError("a length L needs beta (a variable length)")
        if not (np.isfinite(L) and L > 0):
            raise ValueError(f"L must be positive, got {L!r}")
        p = np.asarray(p, dtype=float)
        if p.ndim != 1 or p.size < 4 or p.size % 2 or np.any(np.diff(p) <= 0) \
                or p[-1] - p[0] >= L:
            raise ValueError("p must hold 2N >= 4 increasing positions spanning less than L")
        return p

    # ---- the fields and the reduced system at one state
    def fields(self, p, cutoff=None, L=None):
        """:class:`qsa.reduction.manifold.SpliceFields` at ``p`` on the quadrature (numpy)."""
        p = np.asarray(p, dtype=float)
        return self._reference.fields(p, self._cut(p, cutoff, L), L)

    def evaluate(self, p, cutoff=None, L=None, correction=None):
        """The reduced system at ``p`` (and length ``L``, needs ``beta``), all named.

        ``L``: the current length of the variable-length reduction (default: the fixed
        length); ``correction``: ``False``/``True`` (the Newton-corrected force),
        ``"profile"`` or ``"profile-lag"`` (numpy; default: as the ODE's).
        Returns a :class:`qsa.reduction.backends.FrontEvaluation`.
        """
        p = self._check(p) if L is None else self._check_length(p, L)
        corr = self._corr if correction is None else correction
        ev = self._reference if isinstance(corr, str) else self._evaluator
        return ev.evaluate(p, self._cut(p, cutoff, L), L, corr)

    def _plain(self, p, cutoff):
        """Uncorrected evaluation at the fixed length, without input checks."""
        p = np.asarray(p, dtype=float)
        return self._evaluator.evaluate(p, self._cut(p, cutoff), None, False)

    def energy(self, p, cutoff=None):
        """``E(psi_N(p)) = int alpha^2/2 psi'^2 + W(psi) dsigma`` (``L`` fixed)."""
        return manifold.energy(self.fields(p, cutoff), self.front.alpha, self.front.well)

    def gradient(self, p, cutoff=None):
        """``dE/dp_j = int R_kappa d psi_N/d p_j dsigma``, shape (2N,)."""
        return self._plain(p, cutoff).force

    def normal_velocities(self, p, cutoff=None):
        """``phi_j^perp``: normal velocity per unit ``p_j'`` modulo rigid motions, (M, 2N).

        Also returns the quadrature weights ``dsigma`` (shape (M,)).
        """
        e = self._plain(p, cutoff)
        return e.normal_velocities, e.weights

    def metric(self, p, cutoff=None):
        """The pulled-back metric ``G_ij = int phi_i^perp phi_j^perp dsigma``, (2N, 2N)."""
        return self._plain(p, cutoff).metric

    def constraints(self, p, cutoff=None):
        """``C(p)`` (shape (3,), as :func:`qsa.equilibria.splice_closure`) and ``dC/dp`` (3, 2N)."""
        e = self._plain(p, cutoff)
        return e.closure, e.closure_jacobian

    def slow_correction(self, p, cutoff=None):
        """One Newton step from the splice towards the slow manifold.

        Solves ``(-alpha^2 d^2 + W''(psi_N)) delta = -R_kappa`` modulo the front
        translation modes ``d psi_N / d p_j`` and a constant (``delta`` orthogonal
        to them: the positions and the total turning are kept); see
        :mod:`qsa.reduction.correction`.

        Returns
        -------
        delta : ndarray, shape (M,)
            On :attr:`sigma`.
        R : ndarray, shape (M,)
            The residual ``-alpha^2 kappa'' + W'(kappa)`` of ``psi_N + delta``.
        """
        return self._reference.correct(self.fields(self._check(p), cutoff))

    # ---- the velocity
    def velocity(self, p, cutoff=None, multipliers=False):
        """``F(p)``: the reduced velocity ``p'`` (shape (2N,)); with the multipliers if asked."""
        p = self._check(p)
        sol = self._solve(p, self._cut(p, cutoff), None)
        return (sol[:p.size], sol[p.size:]) if multipliers else sol[:p.size]

    def velocity_length(self, p, L, cutoff=None):
        """``(p', L')`` of the variable-length reduction (needs ``beta``), shapes (2N,), ()."""
        if self.beta is None:
            raise ValueError("velocity_length needs beta (a variable length)")
        p = self._check_length(p, L)
        v = self._solve(p, self._cut(p, cutoff, L), float(L))
        return v[:p.size], float(v[p.size])

    @property
    def _corr(self):
        return {None: False, "newton": True}.get(self.correction, self.correction)

    def _solve(self, p, cut, L):
        return self._evaluator.velocity(p, cut, L, self._corr)

    def rhs(self, y, cutoff):
        """``p'`` (or ``(p', L')`` with ``beta``) at the state ``y = p`` (or ``(p, L)``).

        No input checks (for integrators, whose trial stages may be wild): a singular
        system raises ``numpy.linalg.LinAlgError``. ``cutoff``: ``(l1, l2)``.
        """
        if self.beta is None:
            return self._solve(y, cutoff, None)[:y.size]
        return self._solve(y[:-1], cutoff, y[-1])[:y.size]

    # ---- linearization
    def tangent_basis(self, p, cutoff=None, L=None):
        """Orthonormal basis of the tangent space of the closure and the base point.

        ``{dC/dp . q = 0, sum q = 0}``, shape (2N, 2N - 4); with ``L`` (a variable
        length, needs ``beta``) of ``{dC/dp . q + dC/dL l = 0, sum q = 0}`` in the
        state ``(q, l)``, shape (2N + 1, 2N - 3).
        """
        p = self._check(p) if L is None else self._check_length(p, L)
        e = self.evaluate(p, cutoff, L)  # the closure of the ODE's own manifold
        n = e.velocity.size
        A = np.zeros((4, n))
        A[:3] = e.matrix[n:n + 3, :n]
        A[3, :p.size] = 1.0
        _, _, Vt = np.linalg.svd(A)
        return Vt[4:].T

    def jacobian(self, p, cutoff=None, step=None, L=None):
        """``dF/dp`` by central differences, shape (2N, 2N), and the tangent-space block.

        With ``L`` (needs ``beta``): the Jacobian of ``(p', L')`` in ``(p, L)``, shape
        (2N + 1, 2N + 1), and its block on the length-free tangent space.

        Returns
        -------
        J : ndarray, shape (2N, 2N)
        J_T : ndarray, shape (2N - 4, 2N - 4)
            ``T^T J T`` with ``T`` = :meth:`tangent_basis`: the linearization of the
            reduced flow on the splice manifold; its eigenvalues are the slow
            eigenvalues of the faceting flow at the splice (with ``L``: 2N - 3, the
            perimeter mode among them).
        """
        p = self._check(p) if L is None else self._check_length(p, L)
        cut = self._cut(p, cutoff, L)
        h = 1e-3 * self.front.width if step is None else float(step)
        if L is None:
            y, F = p, (lambda y: self.velocity(y, cut))
        else:
            y = np.append(p, float(L))
            F = (lambda y: np.append(*self.velocity_length(y[:-1], y[-1], cut)))
        n = y.size
        J = np.empty((n, n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            J[:, j] = (F(y + e) - F(y - e)) / (2 * h)
        T = self.tangent_basis(p, cut, L)
        return J, T.T @ J @ T

    def eigenvalues(self, p, cutoff=None, L=None):
        """Eigenvalues of the tangent-space Jacobian (sorted by real part, descending)."""
        ev = np.linalg.eigvals(self.jacobian(p, cutoff, L=L)[1])
        return ev[np.argsort(-ev.real)]

    def crossings(self, p, cutoff=None):
        """Crossings of ``kstar/2`` by the splice profile (the detector's front positions)."""
        prof = self.profile(p, cutoff)
        f = detect_fronts(prof(self.sigma), self.front.kstar, self.length)
        return f.positions

    def integrate(self, p0, t_final, t_eval=None, rtol=1e-8, atol=None, method="auto",
                  max_collisions=10, close=True, redistribute="project"):
        """Integrate ``p' = F(p)`` from ``p0``, removing colliding pairs.

        See :func:`qsa.reduction.integrate.integrate_fronts` for the parameters.

        Returns
        -------
        FrontODEResult
        """
        if not (np.isfinite(t_final) and t_final > 0):
            raise ValueError(f"t_final must be positive, got {t_final!r}")
        return integrate_fronts(self, self._check(p0), t_final, t_eval, rtol, atol, method,
                                max_collisions, close, redistribute)
