"""Validation of the front-position ODE against the DAE faceting flow.

:func:`compare_fronts` starts the DAE faceting flow (:class:`qsa.flows.FacetingFlow`,
``L* = L`` so the perimeter term is balanced) from a splice with unequal facets,
tracks its fronts (:func:`qsa.reduction.track_fronts`), integrates the
front-position ODE (:class:`qsa.reduction.FrontODE`) from the same ``p(0)`` and
compares

* the front positions (``kstar/2`` crossings of both profiles, each set
  shifted to zero mean: the DAE's base node drifts with its tangential gauge,
  the ODE fixes ``sum p' = 0``), in units of the smallest facet;
* the first collision (pair annihilation) times.

Because a closing pair obeys ``d' ~ -c exp(-lambda d)``, a relative rate error
``eps`` makes the position error grow like ``(eps/lambda) x / (1 - x)``,
``x = t / t_c`` (:func:`qsa.reduction.ode.collision_sensitivity`): it is
finite at every ``t < t_c`` but unbounded at the collision itself, so the error
is also reported at fixed fractions of ``t_c`` and with the ODE time rescaled
by the ratio of the collision times (``t -> t t_c^ODE / t_c^DAE``), which
removes the rate error and measures the shape of the trajectory.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from qsa.reduction.fronts import detect_fronts, track_flow
from qsa.reduction.ode import FrontODE

__all__ = ["SCENARIOS", "Scenario", "FrontComparison", "scenario_splice", "compare_fronts",
           "compare_eigenvalues"]


@dataclass(frozen=True)
class Scenario:
    """A rounded polygon (corner angles in degrees, requested facet lengths)."""

    name: str
    angles: tuple
    facets: tuple
    description: str
    t_final: float


#: Built-in scenarios of ``qsa reproduce fronts`` (alpha = 0.1, kstar = 5, beta = 5).
SCENARIOS = {
    "triangle": Scenario(
        "triangle", (130.0, 120.0, 110.0), (0.3, 0.4, 0.5),
        "triangle with unequal sides relaxing: the shortest facet collapses", 3.2),
    "short-facet": Scenario(
        "short-facet", (90.0, 90.0, 80.0, 100.0), (0.5, 0.28, 0.5, 0.35),
        "quadrilateral (right trapezoid) with one short facet that collapses", 0.09),
}


def scenario_splice(scenario, alpha=0.1, kstar=5.0, grid=None):
    """The closed splice of a scenario (:func:`qsa.equilibria.splice_polygon`)."""
    from qsa.equilibria import splice_polygon

    sc = SCENARIOS[scenario] if isinstance(scenario, str) else scenario
    return splice_polygon(np.deg2rad(sc.angles), sc.facets, alpha, kstar=kstar, grid=grid)


@dataclass(frozen=True)
class FrontComparison:
    """Result of :func:`compare_fronts` (times, positions and the summary numbers).

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
    summary : dict
        JSON-ready numbers (see :func:`compare_fronts`).
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
    summary: dict = field(default_factory=dict)


def _centred(P, L):
    """Positions unwrapped against the first row and shifted to zero mean per row."""
    P = np.array(P, dtype=float)
    P = P[0] + ((P - P[0] + 0.5 * L) % L - 0.5 * L)
    return P - P.mean(axis=1, keepdims=True)


def compare_fronts(scenario="triangle", alpha=0.1, kstar=5.0, beta=5.0, N=1200, t_final=None,
                   tol=1e-6, method="bdf2", rtol=1e-4, fractions=(0.5, 0.9, 0.95, 0.99),
                   correction=None, reference_N=None):
    """Run the DAE flow and the front ODE from the same splice and compare them.

    Parameters
    ----------
    scenario : str or Scenario
        ``"triangle"`` or ``"short-facet"`` (:data:`SCENARIOS`).
    alpha, kstar, beta : float
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
    correction : {None, "newton"}
        Force correction of both reductions (:class:`qsa.reduction.FrontODE`).
    reference_N : int, optional
        Also run the DAE at this resolution and report how far its fronts are from
        the compared DAE run's (``summary["dae_spread"]``: ``error_at``, ``max_error``
        up to the first collision, ``collision_rel_diff``, in the same units): the
        reference's own resolution error, the scale against which the reduction's
        errors near the collision are to be read.

    Returns
    -------
    FrontComparison
        ``summary`` keys: ``collision_dae``, ``collision_ode``,
        ``collision_rel_diff``, ``max_error`` (largest error before the first
        collision of either model, at DAE snapshots, / smallest facet),
        ``max_error_separated`` (the same while every DAE gap is at least
        ``2 d_c``, i.e. while the splice manifold describes the state;
        ``separated_until`` the last such time / ``t_c``), ``collision_distance``,
        ``error_at`` (``{fraction: error}``), ``max_error_rescaled`` (ODE time
        rescaled by ``t_c^ODE / t_c^DAE``), ``time_dae``, ``time_ode``,
        ``speedup``, ``n_steps_dae``, ``nfev_ode``, ``N``, ``facet_min``, and
        ``variable_length``: the same numbers for the reduction with the length as an
        unknown (``FrontODE(beta=beta)``, ``method="auto"``; positions compared as ``p``, which
        differ from the crossings by the neighbours' tails only; also with
        ``max_error_separated`` and ``separated_until``).
    """
    sc = SCENARIOS[scenario] if isinstance(scenario, str) else scenario
    t_final = sc.t_final if t_final is None else float(t_final)
    p0, L, facet_min, dae_run = _dae_fronts(sc, alpha, kstar, beta, N, t_final, tol, method)
    t, dae, tc_dae, res, time_dae = dae_run

    ode = FrontODE(alpha, kstar, L, correction=correction)
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
    error_at = {}
    for f in fractions:
        sel = before & (t <= f * tc_dae)
        error_at[str(f)] = float(np.max(error[sel])) if np.any(sel) else np.nan
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
    variable = _variable_length(p0, L, alpha, kstar, beta, t_final, t, dae, tc_dae, facet_min,
                                fractions, time_dae, wide, correction=correction)
    summary = {
        "scenario": sc.name, "description": sc.description, "alpha": alpha, "kstar": kstar,
        "beta": beta, "N": int(N), "L": float(L), "facet_min": facet_min,
        "correction": correction,
        "collision_dae": float(tc_dae), "collision_ode": float(tc_ode),
        "collision_rel_diff": float(abs(tc_ode - tc_dae) / tc_dae),
        "max_error": float(np.max(error[before])) if np.any(before) else np.nan,
        "error_at": error_at, "max_error_rescaled": rescaled,
        "max_error_separated": float(np.max(error[sep])) if np.any(sep) else np.nan,
        "separated_until": float(t[sep][-1] / tc_dae) if np.any(sep) else np.nan,
        "collision_distance": float(dc),
        "time_dae": time_dae, "time_ode": time_ode, "speedup": time_dae / time_ode,
        "n_steps_dae": int(res.n_steps), "nfev_ode": int(sol.nfev),
        "dae_message": res.message, "ode_message": sol.message,
        "variable_length": variable,
    }
    if reference_N is not None:
        summary["dae_spread"] = _dae_spread(sc, alpha, kstar, beta, int(reference_N), t_final,
                                            tol, method, t, dae, tc_dae, facet_min, fractions)
    p_ode = seg.p - seg.p.mean(axis=1, keepdims=True)
    return FrontComparison(t, dae, P, seg.t, p_ode, float(tc_dae), float(tc_ode), facet_min,
                           error, summary)


def _dae_fronts(sc, alpha, kstar, beta, N, t_final, tol, method):
    """The DAE flow from the scenario's splice, tracked to its first collision.

    Returns ``p0, L, facet_min`` and ``(t, positions, t_c, result, cpu seconds)``
    (positions: ``kstar/2`` crossings, zero mean, at the snapshots while all fronts live).
    """
    from qsa import FiniteDifference
    from qsa.flows import FacetingFlow, solve_flow

    eq = scenario_splice(sc, alpha, kstar, grid=FiniteDifference(N))
    p0 = np.array(eq.params["positions"])
    L = eq.params["L"]
    n_fronts = p0.size
    gaps0 = np.diff(np.append(p0, p0[0] + L))
    facet_min = float(gaps0[1::2].min())

    def stop(t, y, system):
        return detect_fronts(system.curvature(y), kstar, system.length(y)).n < n_fronts

    start = time.process_time()
    res = solve_flow(FacetingFlow(alpha, kstar, beta, L), eq.curve.positions(), t_final, N=N,
                     tol=tol, method=method, callback=stop, progress=False)
    cpu = time.process_time() - start
    tracks = track_flow(res, kstar)
    tc = tracks.first_collision.time if tracks.events else np.nan
    alive = np.all(np.isfinite(tracks.positions), axis=1)
    return p0, L, facet_min, (res.t[alive], _centred(tracks.positions[alive], L), tc, res, cpu)


def _dae_spread(sc, alpha, kstar, beta, N_ref, t_final, tol, method, t, dae, tc_dae, facet_min,
                fractions):
    """How far the DAE at ``N_ref`` is from the compared DAE run (its own resolution error)."""
    _, _, _, (t2, dae2, tc2, _, _) = _dae_fronts(sc, alpha, kstar, beta, N_ref, t_final, tol,
                                                  method)
    m = t < min(tc_dae, tc2)
    P = np.column_stack([np.interp(t[m], t2, dae2[:, j]) for j in range(dae.shape[1])])
    err = np.max(np.abs(P - dae[m]), axis=1) / facet_min
    out = {"N": int(N_ref), "collision": float(tc2),
           "collision_rel_diff": float(abs(tc2 - tc_dae) / tc_dae),
           "max_error": float(err.max()) if err.size else np.nan, "error_at": {}}
    for f in fractions:
        sel = t[m] <= f * tc_dae
        out["error_at"][str(f)] = float(err[sel].max()) if np.any(sel) else np.nan
    return out


def _variable_length(p0, L, alpha, kstar, beta, t_final, t, dae, tc_dae, facet_min, fractions,
                     time_dae, wide, rtol=1e-4, correction=None):
    """Collision time and position errors of the variable-length reduction.

    ``wide`` marks the DAE snapshots at which every gap is at least ``2 d_c``.
    """
    ode = FrontODE(alpha, kstar, L, beta=beta, correction=correction)
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
    error = np.max(np.abs(P - dae), axis=1) / facet_min
    finite = [v for v in (tc_dae, tc) if np.isfinite(v)]
    before = (t < (min(finite) if finite else np.inf)) & np.isfinite(error)
    error_at = {}
    for f in fractions:
        sel = before & (t <= f * tc_dae)
        error_at[str(f)] = float(np.max(error[sel])) if np.any(sel) else np.nan
    sep = before & wide
    return {"beta": beta, "collision_ode": float(tc),
            "collision_rel_diff": float(abs(tc - tc_dae) / tc_dae), "error_at": error_at,
            "max_error": float(np.max(error[before])) if np.any(before) else np.nan,
            "max_error_separated": float(np.max(error[sep])) if np.any(sep) else np.nan,
            "separated_until": float(t[sep][-1] / tc_dae) if np.any(sep) else np.nan,
            "time_ode": cpu, "speedup": time_dae / cpu, "nfev_ode": int(sol.nfev),
            "L_change": float(sol.segments[0].L[-1] - L)}


def compare_eigenvalues(n_corners=3, facet=0.35, alpha=0.1, kstar=5.0, N=285,
                        angles=None, facets=None):
    """Slow eigenvalues of the reduced Jacobian against the full linearization.

    The full linearization (``qsa.spectra.spectrum``, ``gauge="normal"``, the
    operator ``J = -[M^dagger L_Lambda M(., 0)]_1``) is only a linearization at an
    equilibrium, so the splice (by default a regular polygon with equal facets,
    an equilibrium by symmetry up to exponentially small terms) is polished
    first (:func:`qsa.equilibria.polish`); the reduced Jacobian
    (:meth:`FrontODE.eigenvalues`) is taken at the splice positions. Of the full
    spectrum the ``2N - 1`` eigenvalues nearest 0 are the three rigid motions
    (discretely ``~ eps |J|``) and the ``2N - 4`` slow front modes.

    Returns
    -------
    dict
        ``reduced``, ``full`` (matched, sorted descending), ``rigid``,
        ``max_rel_diff``, ``polish_residual``, ``N``.
    """
    import warnings

    from qsa import Fourier
    from qsa.equilibria import polish, splice_polygon
    from qsa.spectra import spectrum

    ang = np.full(n_corners, 2 * np.pi / n_corners) if angles is None else np.deg2rad(angles)
    fac = np.full(n_corners, facet) if facets is None else np.asarray(facets, dtype=float)
    eq = splice_polygon(ang, fac, alpha, kstar=kstar, grid=Fourier(N))
    p = np.array(eq.params["positions"])
    red = FrontODE(alpha, kstar, eq.params["L"]).eigenvalues(p)
    pol = polish(eq.energy, eq.curve)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        spec = spectrum(pol.energy, pol.curve, gauge="normal")
    ev = np.real(np.asarray(spec.eigenvalues))
    near = ev[np.argsort(np.abs(ev))][: red.size + 3]  # sorted by |lambda|
    rigid, slow = near[:3], np.sort(near[3:])[::-1]
    red = np.sort(np.real(red))[::-1]
    rel = np.abs(red - slow) / np.abs(slow)
    return {"reduced": red.tolist(), "full": slow.tolist(), "rigid": rigid.tolist(),
            "max_rel_diff": float(rel.max()), "polish_residual": float(pol.residual),
            "polish_success": bool(pol.success), "N": int(N), "n_corners": int(n_corners)}
