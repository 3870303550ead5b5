"""Validation of the front-position ODE against the DAE faceting flow and the spectrum.

:func:`compare_fronts` takes a :class:`~qsa.paper.scenarios.Scenario` (a rounded
polygon with its energy parameters), starts the DAE faceting flow
(:class:`qsa.flows.FacetingFlow`, ``L* = L`` so the perimeter term is balanced)
from its splice with unequal facets,
tracks its fronts (:func:`qsa.reduction.track_fronts`), integrates the
front-position ODE (:class:`qsa.reduction.FrontODE`) from the same ``p(0)`` and
compares

* the front positions (``kstar/2`` crossings of both profiles, each set
  shifted to zero mean: the DAE's base node drifts with its tangential gauge,
  the ODE fixes ``sum p' = 0``), in units of the smallest facet;
* the first collision (pair annihilation) times.

Because a closing pair obeys ``d' ~ -c exp(-lambda d)``, a relative rate error
``eps`` makes the position error grow like ``(eps/lambda) x / (1 - x)``,
``x = t / t_c`` (:func:`qsa.reduction.collision_sensitivity`): it is
finite at every ``t < t_c`` but unbounded at the collision itself, so the error
is also reported at fixed fractions of ``t_c`` and with the ODE time rescaled
by the ratio of the collision times (``t -> t t_c^ODE / t_c^DAE``), which
removes the rate error and measures the shape of the trajectory.

:func:`compare_eigenvalues` (:mod:`qsa.paper.eigenvalues`, importable from here) compares
the slow eigenvalues of the reduced Jacobian with the full linearization mode by mode.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsa import FiniteDifference
from qsa.flows import FacetingFlow, solve_flow
from qsa.paper.eigenvalues import EigenvalueComparison, compare_eigenvalues
from qsa.paper.results import _Summarised
from qsa.paper.scenarios import SCENARIOS, Scenario, front_scenario, scenario_splice
from qsa.reduction import FrontODE, detect_fronts, track_flow

__all__ = ["SCENARIOS", "Scenario", "FrontComparison", "VariableLengthComparison", "DAESpread",
           "EigenvalueComparison", "scenario_splice", "compare_fronts", "compare_eigenvalues"]

#: fractions of the DAE collision time at which position errors are reported
FRACTIONS = (0.5, 0.9, 0.95, 0.99)


def _max_or_nan(values, mask):
    return float(np.max(values[mask])) if np.any(mask) else np.nan


def _error_at(t, error, mask, t_c, fractions):
    """``{str(f): max error over mask & (t <= f t_c)}``."""
    return {str(f): _max_or_nan(error, mask & (t <= f * t_c)) for f in fractions}


@dataclass(frozen=True, eq=False)
class VariableLengthComparison:
    """The reduction with the length as an unknown against the DAE (see :func:`compare_fronts`).

    Positions are compared as ``p`` (which differ from the crossings by the
    neighbours' tails only); ``L_change`` is the ODE's final minus initial length.
    """

    beta: float
    collision_ode: float
    collision_rel_diff: float
    error_at: dict
    max_error: float
    max_error_separated: float
    separated_until: float
    time_ode: float
    speedup: float
    n_rhs_ode: int
    L_change: float

    @property
    def nfev_ode(self) -> int:
        """Read-only alias of ``n_rhs_ode`` (the former name)."""
        return self.n_rhs_ode

    def summary(self):
        return {"beta": self.beta, "collision_ode": self.collision_ode,
                "collision_rel_diff": self.collision_rel_diff, "error_at": self.error_at,
                "max_error": self.max_error, "max_error_separated": self.max_error_separated,
                "separated_until": self.separated_until, "time_ode": self.time_ode,
                "speedup": self.speedup, "n_rhs_ode": self.n_rhs_ode, "L_change": self.L_change}


@dataclass(frozen=True, eq=False)
class DAESpread:
    """The DAE at another resolution ``N`` against the compared DAE run (same units)."""

    N: int
    collision: float
    collision_rel_diff: float
    max_error: float
    error_at: dict

    def summary(self):
        return {"N": self.N, "collision": self.collision,
                "collision_rel_diff": self.collision_rel_diff, "max_error": self.max_error,
                "error_at": self.error_at}


@dataclass(frozen=True, eq=False)
class FrontComparison(_Summarised):
    """Result of :func:`compare_fronts`: trajectories of both models and their errors.

    Attributes
    ----------
    t : ndarray, shape (n,)
        DAE snapshot times up to its first collision.
    dae, ode : ndarray, shape (n, 2N)
        Front positions (``kstar/2`` crossings, zero mean) of both models at ``t``;
        ODE rows after its own collision are NaN.
    t_ode : ndarray
        ODE output times (dense, for plotting), ``p_ode`` its positions (zero mean).
    collision_dae, collision_ode : float
        First collision times (NaN if none before ``t_final``).
    facet_min : float
        Smallest facet length at ``t = 0``.
    error : ndarray, shape (n,)
        ``max_i |p_ode - p_dae| / facet_min`` at ``t``.
    scenario : Scenario
    N : int
        DAE nodes.
    L : float
        Length of the splice.
    correction : None or "newton"
    error_at : dict of str -> float
        Largest error up to each fraction of the DAE collision time.
    max_error : float
        Largest error before the first collision of either model.
    max_error_rescaled : float
        The same with the ODE time rescaled by ``t_c^ODE / t_c^DAE``.
    max_error_separated, separated_until : float
        Largest error while every DAE gap is at least ``2 d_c`` (the splice
        manifold describes the state), and the last such time / ``t_c``.
    collision_distance : float
        ``d_c`` of the front.
    time_dae, time_ode : float
        CPU seconds.
    n_steps_dae, n_rhs_ode : int
        Accepted DAE steps; evaluations of the ODE's right-hand side (``nfev_ode`` is a
        read-only alias).
    dae_message, ode_message : str
    variable_length : VariableLengthComparison or None
        The same for the reduction with the length as an unknown (``beta`` of the
        scenario).
    dae_spread : DAESpread or None
        With ``reference_N``.
    """

    t: np.ndarray
    dae: np.ndarray
    ode: np.ndarray
    t_ode: np.ndarray
    p_ode: np.ndarray
    collision_dae: float
    collision_ode: float
    facet_min: float
    error: np.ndarray
    scenario: Scenario
    N: int
    L: float
    correction: str | None
    error_at: dict
    max_error: float
    max_error_rescaled: float
    max_error_separated: float
    separated_until: float
    collision_distance: float
    time_dae: float
    time_ode: float
    n_steps_dae: int
    n_rhs_ode: int
    dae_message: str
    ode_message: str
    variable_length: VariableLengthComparison | None
    dae_spread: DAESpread | None = None

    @property
    def nfev_ode(self) -> int:
        """Read-only alias of :attr:`n_rhs_ode` (the former name)."""
        return self.n_rhs_ode

    @property
    def collision_rel_diff(self):
        """``|t_c^ODE - t_c^DAE| / t_c^DAE``."""
        return float(abs(self.collision_ode - self.collision_dae) / self.collision_dae)

    @property
    def speedup(self):
        return self.time_dae / self.time_ode

    def summary(self):
        """The JSON summary (``qsa reproduce fronts --json``)."""
        sc = self.scenario
        out = {
            "scenario": sc.name, "description": sc.description, "alpha": sc.alpha,
            "kstar": sc.kstar, "beta": sc.beta, "N": self.N, "L": self.L,
            "facet_min": self.facet_min, "correction": self.correction,
            "collision_dae": self.collision_dae, "collision_ode": self.collision_ode,
            "collision_rel_diff": self.collision_rel_diff,
            "max_error": self.max_error, "error_at": self.error_at,
            "max_error_rescaled": self.max_error_rescaled,
            "max_error_separated": self.max_error_separated,
            "separated_until": self.separated_until,
            "collision_distance": self.collision_distance,
            "time_dae": self.time_dae, "time_ode": self.time_ode, "speedup": self.speedup,
            "n_steps_dae": self.n_steps_dae, "n_rhs_ode": self.n_rhs_ode,
            "dae_message": self.dae_message, "ode_message": self.ode_message,
            "variable_length": (None if self.variable_length is None
                                else self.variable_length.summary()),
        }
        if self.dae_spread is not None:
            out["dae_spread"] = self.dae_spread.summary()
        return out


def _centred(P, L):
    """Positions unwrapped against the first row and shifted to zero mean per row."""
    P = np.array(P, dtype=float)
    P = P[0] + ((P - P[0] + 0.5 * L) % L - 0.5 * L)
    return P - P.mean(axis=1, keepdims=True)


def compare_fronts(scenario="triangle", *, N=1200, t_final=None, tol=1e-6, method="bdf2",
                   rtol=1e-4, fractions=FRACTIONS, correction=None, reference_N=None,
                   alpha=None, kstar=None, beta=None, progress=False):
    """Run the DAE flow and the front ODE from the same splice and compare them.

    Parameters
    ----------
    scenario : str or Scenario
        ``"triangle"`` or ``"short-facet"`` (:data:`SCENARIOS`), or any
        :class:`~qsa.paper.scenarios.Scenario`; it carries ``alpha``, ``kstar``,
        ``beta`` and ``t_final``.
    N : int
        DAE nodes (second-order finite differences: the collision time converges
        like ``N^-2``).
    t_final : float, optional
        Default the scenario's.
    tol, method
        DAE local error tolerance and method (:func:`qsa.flows.solve_flow`).
    rtol : float
        ODE tolerance (RK45; ``1e-4`` puts the collision time within ~1e-4 of its
        converged value, far below the model error).
    fractions : tuple of float
        Fractions of the DAE collision time at which the error is reported.
    correction : {None, "newton", "profile", "profile-lag"}
        Force correction (or manifold) of both reductions, fixed and variable
        length (:class:`qsa.reduction.FrontODE`).
    reference_N : int, optional
        Also run the DAE at this resolution and report how far its fronts are from
        the compared DAE run's (``dae_spread``: ``error_at``, ``max_error`` up to the
        first collision, ``collision_rel_diff``, in the same units): the
        reference's own resolution error, the scale against which the reduction's
        errors near the collision are to be read.
    alpha, kstar, beta : float, optional
        Replace the scenario's values.
    progress : bool or None
        Progress bar of the DAE runs (:func:`qsa.flows.solve_flow`; ``None``: on a
        terminal).

    Returns
    -------
    FrontComparison
        Besides the trajectories: the collision times, the position errors (up to
        fractions of ``t_c``, up to the first collision, while the splice manifold
        describes the state, with the ODE time rescaled), CPU times, and
        ``variable_length``: the same numbers for the reduction with the length as
        an unknown (``FrontODE(beta=beta)``, ``method="auto"``).
        ``summary()`` is the JSON of ``qsa reproduce fronts --json``.
    """
    sc = front_scenario(scenario, alpha=alpha, kstar=kstar, beta=beta)
    t_final = sc.t_final if t_final is None else float(t_final)
    ref = _dae_fronts(sc, N, t_final, tol, method, progress)
    t, dae, tc_dae, L, p0, facet_min = ref.t, ref.positions, ref.t_c, ref.L, ref.p0, ref.facet_min

    ode = FrontODE(sc.alpha, sc.kstar, L, correction=correction)
    # warm-up: loads (or compiles) the numba kernels outside the timing
    ode.integrate(p0, 1e-6 * t_final, rtol=rtol, max_collisions=0)
    start = time.process_time()
    sol = ode.integrate(p0, t_final, rtol=rtol, max_collisions=0)
    time_ode = time.process_time() - start
    tc_ode = sol.first_collision.time if sol.events else np.nan
    seg = sol.segments[0]

    m = t <= (tc_ode if np.isfinite(tc_ode) else np.inf)
    sol_t = ode.integrate(p0, t_final, t_eval=t[m], rtol=rtol, max_collisions=0)
    P = np.full(dae.shape, np.nan)
    cross = np.array([ode.crossings(q) for q in sol_t.segments[0].p])
    if cross.size:
        Q = sol_t.segments[0].p
        cross = Q + ((cross - Q + 0.5 * L) % L - 0.5 * L)
        P[: cross.shape[0]] = cross - cross.mean(axis=1, keepdims=True)
    error = np.max(np.abs(P - dae), axis=1) / facet_min
    finite = [v for v in (tc_dae, tc_ode) if np.isfinite(v)]
    tc = min(finite) if finite else np.inf
    before = (t < tc) & np.isfinite(error)
    rescaled = np.nan
    if np.isfinite(tc_dae) and np.isfinite(tc_ode):
        ts = t[t < tc_dae] * (tc_ode / tc_dae)
        sol_s = ode.integrate(p0, t_final, t_eval=ts[ts < tc_ode], rtol=rtol, max_collisions=0)
        Qs = sol_s.segments[0].p
        cs = np.array([ode.crossings(q) for q in Qs])
        if cs.ndim == 2 and cs.shape[1] == p0.size:
            cs = Qs + ((cs - Qs + 0.5 * L) % L - 0.5 * L)
            cs -= cs.mean(axis=1, keepdims=True)
            rescaled = float(np.max(np.abs(cs - dae[: cs.shape[0]])) / facet_min)
    # validity of the splice manifold: both fronts of every pair still separated
    dc = ode.collision_distance
    gaps_dae = np.min(np.abs(np.diff(np.sort(dae, axis=1), axis=1)), axis=1)
    wide = gaps_dae >= 2 * dc
    sep = before & wide
    variable = _variable_length(sc, ref, t_final, fractions, wide, correction=correction)
    spread = None if reference_N is None else _dae_spread(sc, int(reference_N), t_final, tol,
                                                          method, ref, fractions)
    return FrontComparison(
        t, dae, P, seg.t, seg.p - seg.p.mean(axis=1, keepdims=True), float(tc_dae),
        float(tc_ode), facet_min, error, scenario=sc, N=int(N), L=float(L),
        correction=correction, error_at=_error_at(t, error, before, tc_dae, fractions),
        max_error=_max_or_nan(error, before), max_error_rescaled=rescaled,
        max_error_separated=_max_or_nan(error, sep),
        separated_until=float(t[sep][-1] / tc_dae) if np.any(sep) else np.nan,
        collision_distance=float(dc), time_dae=ref.cpu, time_ode=time_ode,
        n_steps_dae=int(ref.result.n_steps), n_rhs_ode=int(sol.n_rhs),
        dae_message=ref.result.message, ode_message=sol.message, variable_length=variable,
        dae_spread=spread)


@dataclass(frozen=True, eq=False)
class _DAEFronts:
    """The DAE flow from a scenario's splice, tracked to its first collision.

    ``p0``, ``L``, ``facet_min`` of the splice; ``t``, ``positions`` (``kstar/2``
    crossings, zero mean) at the snapshots while all fronts live; ``t_c`` the first
    collision; ``result`` the flow result; ``cpu`` its CPU seconds.
    """

    p0: np.ndarray
    L: float
    facet_min: float
    t: np.ndarray
    positions: np.ndarray
    t_c: float
    result: object
    cpu: float


def _dae_fronts(sc, N, t_final, tol, method, progress=False):
    eq = sc.splice(FiniteDifference(N))
    p0 = np.array(eq.params["positions"])
    L = eq.params["L"]
    n_fronts = p0.size
    gaps0 = np.diff(np.append(p0, p0[0] + L))
    facet_min = float(gaps0[1::2].min())

    def stop(t, y, system):
        return detect_fronts(system.curvature(y), sc.kstar, system.length(y)).n < n_fronts

    start = time.process_time()
    res = solve_flow(FacetingFlow(sc.alpha, sc.kstar, sc.beta, L), eq.curve.positions(),
                     t_final, N=N, tol=tol, method=method, callback=stop, progress=progress)
    cpu = time.process_time() - start
    tracks = track_flow(res, sc.kstar)
    tc = tracks.first_collision.time if tracks.events else np.nan
    alive = np.all(np.isfinite(tracks.positions), axis=1)
    return _DAEFronts(p0, L, facet_min, res.t[alive], _centred(tracks.positions[alive], L), tc,
                      res, cpu)


def _dae_spread(sc, N_ref, t_final, tol, method, ref, fractions):
    """How far the DAE at ``N_ref`` is from the compared DAE run (its own resolution error)."""
    other = _dae_fronts(sc, N_ref, t_final, tol, method)
    t, dae, tc_dae = ref.t, ref.positions, ref.t_c
    m = t < min(tc_dae, other.t_c)
    P = np.column_stack([np.interp(t[m], other.t, other.positions[:, j])
                         for j in range(dae.shape[1])])
    err = np.max(np.abs(P - dae[m]), axis=1) / ref.facet_min
    return DAESpread(int(N_ref), float(other.t_c),
                     float(abs(other.t_c - tc_dae) / tc_dae),
                     float(err.max()) if err.size else np.nan,
                     _error_at(t[m], err, np.ones(err.size, bool), tc_dae, fractions))


def _variable_length(sc, ref, t_final, fractions, wide, rtol=1e-4, correction=None):
    """Collision time and position errors of the variable-length reduction.

    ``wide`` marks the DAE snapshots at which every gap is at least ``2 d_c``.
    """
    p0, L, t, dae, tc_dae = ref.p0, ref.L, ref.t, ref.positions, ref.t_c
    ode = FrontODE(sc.alpha, sc.kstar, L, beta=sc.beta, correction=correction)
    ode.integrate(p0, 1e-6 * t_final, rtol=rtol, method="auto", max_collisions=0)  # warm-up
    start = time.process_time()
    sol = ode.integrate(p0, t_final, rtol=rtol, method="auto", max_collisions=0)
    cpu = time.process_time() - start
    tc = sol.first_collision.time if sol.events else np.nan
    m = t <= (tc if np.isfinite(tc) else np.inf)
    Q = ode.integrate(p0, t_final, t_eval=t[m], rtol=rtol, method="auto",
                      max_collisions=0).segments[0].p
    P = np.full(dae.shape, np.nan)
    P[: Q.shape[0]] = Q - Q.mean(axis=1, keepdims=True)
    error = np.max(np.abs(P - dae), axis=1) / ref.facet_min
    finite = [v for v in (tc_dae, tc) if np.isfinite(v)]
    before = (t < (min(finite) if finite else np.inf)) & np.isfinite(error)
    sep = before & wide
    return VariableLengthComparison(
        beta=sc.beta, collision_ode=float(tc), collision_rel_diff=float(abs(tc - tc_dae) / tc_dae),
        error_at=_error_at(t, error, before, tc_dae, fractions),
        max_error=_max_or_nan(error, before), max_error_separated=_max_or_nan(error, sep),
        separated_until=float(t[sep][-1] / tc_dae) if np.any(sep) else np.nan,
        time_ode=cpu, speedup=ref.cpu / cpu, n_rhs_ode=int(sol.n_rhs),
        L_change=float(sol.segments[0].L[-1] - L))
