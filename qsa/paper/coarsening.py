"""Multi-event coarsening: the front-position ODE against the DAE, event by event.

:func:`compare_coarsening` runs the DAE faceting flow -- f:facet's spinodal start
(:class:`~qsa.paper.scenarios.FacetScenario`) or a rounded polygon's splice
(:class:`~qsa.paper.scenarios.Scenario`) -- recording the curvature at every accepted
step, hands the state over to the front ODE (:class:`qsa.reduction.FrontODE`, length
free with the flow's ``beta`` and ``L*``) once the fronts have formed, and integrates
the ODE through all its collisions (:meth:`FrontODE.integrate`). Both event sequences
are written in the fronts' identities at the hand-over (the detector's order,
:func:`qsa.reduction.hand_over`): which pair annihilated, whether it closed a corner
(an up-front followed by a down-front) or a facet, when, and how many fronts remain.

*Hand-over.* The reduction describes the flow near the splice manifold only, where
the profile is quasi-steady. The default hand-over time is the first accepted step at
which the front count has reached its peak, the functional residual ``R_kappa``
(:func:`qsa.flows.analysis.functional_residual`) is at most ``residual_max`` and every
gap is at least twice the collision distance ``d_c``. Before that the fronts are still
forming: annihilations during the spinodal transient are reported
(:attr:`CoarseningComparison.before_handover`) but not carried by the ODE. The length
of the ODE is the flow's at the hand-over, its ``L*`` the flow's ``L*`` (the curve is
still relaxing its length then; the ODE's variable length follows it).

*Events.* A DAE event is the first step at which a pair's crossings have vanished
(:func:`qsa.reduction.track_fronts`, the mid-point of the bracketing steps); an ODE
event the time at which a gap reaches ``d_c``, where the superposed splice pair stops
crossing ``kstar/2`` -- the same criterion.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from qsa import FiniteDifference
from qsa.flows import FacetingFlow, solve_flow
from qsa.flows.analysis import functional_residual
from qsa.paper.results import _Summarised, coarsening_events
from qsa.paper.runs import run_facet
from qsa.paper.scenarios import FacetScenario, Scenario
from qsa.reduction import FrontODE, detect_fronts, track_fronts
from qsa.reduction.handover import hand_over

__all__ = ["SequenceEvent", "FrontState", "CoarseningComparison", "DAECoarsening",
           "dae_coarsening", "compare_coarsening"]


@dataclass(frozen=True)
class SequenceEvent:
    """One annihilation of a coarsening sequence.

    Attributes
    ----------
    time : float
    n_fronts : int
        Fronts left after it.
    fronts : (int, int)
        The pair, as indices of the fronts at the hand-over (detector order),
        in cyclic order along the curve.
    kind : str
        ``"corner"`` (the pair closed a corner: up- then down-front) or ``"facet"``.
    """

    time: float
    n_fronts: int
    fronts: tuple
    kind: str

    def summary(self):
        return {"time": self.time, "n_fronts": self.n_fronts, "fronts": list(self.fronts),
                "kind": self.kind}


@dataclass(frozen=True)
class FrontState:
    """Corners and facets of a state, cyclically from the first surviving up-front.

    ``corner_turning`` is ``kstar`` times each corner's length (its turning angle),
    ``facet_lengths`` the facets' lengths, ``fronts`` the surviving fronts' indices at
    the hand-over.
    """

    time: float
    fronts: tuple
    corner_turning: tuple
    facet_lengths: tuple
    length: float

    def summary(self):
        return {"time": self.time, "fronts": list(self.fronts),
                "corner_turning": list(self.corner_turning),
                "facet_lengths": list(self.facet_lengths), "length": self.length}


@dataclass(frozen=True, eq=False)
class CoarseningComparison(_Summarised):
    """Result of :func:`compare_coarsening`.

    Attributes
    ----------
    scenario : FacetScenario or Scenario
    N, method, tol
        The DAE's nodes, time stepper and tolerance.
    correction, redistribute
        The ODE's force correction and where a removed pair's turning goes.
    handover_time : float
    handover_fronts : int
    handover_residual : float
        ``R_kappa`` at the hand-over.
    handover_mismatch : float
        Largest difference of the splice's crossings from the DAE's after closing.
    before_handover : tuple of (float, int)
        DAE front-count drops before the hand-over: ``(time, fronts left)``.
    dae_events, ode_events : tuple of SequenceEvent
    t_dae : ndarray, shape (n,)
    dae_positions : ndarray, shape (n, 2N)
        DAE front positions from the hand-over on (columns: the fronts at the
        hand-over), NaN once annihilated; the common drift of the surviving fronts
        (the DAE's tangential gauge) removed.
    t_ode : ndarray, shape (m,)
    ode_positions : ndarray, shape (m, 2N)
        The same for the ODE (its ``p``).
    final_dae, final_ode : FrontState
        At the last DAE step and the ODE's end (``t_final``).
    t_final : float
    time_dae, time_ode : float
        CPU seconds (the DAE's whole run; the ODE's from the hand-over).
    n_rhs_ode : int
        Evaluations of the ODE's right-hand side (``nfev_ode`` is a read-only alias).
    dae_success, ode_success : bool
    dae_message, ode_message : str
    """

    scenario: object
    N: int
    method: str
    tol: float
    correction: str | None
    redistribute: str
    handover_time: float
    handover_fronts: int
    handover_residual: float
    handover_mismatch: float
    before_handover: tuple
    dae_events: tuple
    ode_events: tuple
    t_dae: np.ndarray
    dae_positions: np.ndarray
    t_ode: np.ndarray
    ode_positions: np.ndarray
    final_dae: FrontState
    final_ode: FrontState
    t_final: float
    time_dae: float
    time_ode: float
    n_rhs_ode: int
    dae_success: bool
    ode_success: bool
    dae_message: str
    ode_message: str

    @property
    def nfev_ode(self) -> int:
        """Read-only alias of :attr:`n_rhs_ode` (the former name)."""
        return self.n_rhs_ode

    @property
    def same_sequence(self):
        """The same pairs annihilate in the same order in both models."""
        a = [frozenset(e.fronts) for e in self.dae_events]
        b = [frozenset(e.fronts) for e in self.ode_events]
        return a == b

    @property
    def event_rel_diff(self):
        """``|t_ODE - t_DAE| / (t_DAE - t_handover)`` per event of equal index and pair.

        Relative to the time since the hand-over (the ODE's own integration time);
        NaN where the pairs differ.
        """
        out = []
        for d, o in zip(self.dae_events, self.ode_events, strict=False):
            same = frozenset(d.fronts) == frozenset(o.fronts)
            span = d.time - self.handover_time
            out.append(abs(o.time - d.time) / span if same and span > 0 else np.nan)
        return np.array(out)

    @property
    def max_event_rel_diff(self):
        r = self.event_rel_diff
        if not self.same_sequence or r.size == 0:
            return np.nan
        return float(np.max(r))

    @property
    def speedup(self):
        return self.time_dae / self.time_ode if self.time_ode > 0 else np.nan

    def summary(self):
        """The JSON of ``qsa reproduce coarsening --json``."""
        sc = self.scenario
        return {
            "scenario": getattr(sc, "name", "facet"), "N": self.N, "method": self.method,
            "tol": self.tol, "correction": self.correction,
            "redistribute": self.redistribute, "t_final": self.t_final,
            "handover_time": self.handover_time, "handover_fronts": self.handover_fronts,
            "handover_residual": self.handover_residual,
            "handover_mismatch": self.handover_mismatch,
            "before_handover": [{"time": t, "n_fronts": n} for t, n in self.before_handover],
            "dae_events": [e.summary() for e in self.dae_events],
            "ode_events": [e.summary() for e in self.ode_events],
            "same_sequence": self.same_sequence,
            "event_rel_diff": [None if np.isnan(x) else float(x) for x in self.event_rel_diff],
            "max_event_rel_diff": self.max_event_rel_diff,
            "final_dae": self.final_dae.summary(), "final_ode": self.final_ode.summary(),
            "time_dae": self.time_dae, "time_ode": self.time_ode, "speedup": self.speedup,
            "n_rhs_ode": self.n_rhs_ode, "dae_success": self.dae_success,
            "ode_success": self.ode_success, "dae_message": self.dae_message,
            "ode_message": self.ode_message,
        }


@dataclass(frozen=True, eq=False)
class DAECoarsening:
    """A DAE run recorded at every accepted step (:func:`dae_coarsening`).

    Attributes
    ----------
    scenario : FacetScenario or Scenario
    N, method, tol, t_final
    t : ndarray, shape (n,)
    kappa : list of ndarray
        Curvature on the uniform nodes at each step.
    length, residual : ndarray, shape (n,)
        ``L`` and ``R_kappa``.
    counts : ndarray of int, shape (n,)
        Number of fronts.
    splice : (ndarray, float) or None
        For a polygon: its splice positions and length (the DAE's start).
    cpu : float
        CPU seconds.
    success : bool
    message : str
    """

    scenario: object
    N: int
    method: str
    tol: float
    t_final: float
    t: np.ndarray
    kappa: list
    length: np.ndarray
    residual: np.ndarray
    counts: np.ndarray
    splice: tuple | None
    cpu: float
    success: bool
    message: str


def _recorder(kstar):
    rows = []

    def callback(t, y, system):
        u = system.unpack(y)
        k = np.array(u["kappa"], dtype=float)
        rows.append((float(t), k, float(u["L"]), functional_residual(u["mu"]),
                     detect_fronts(k, kstar, float(u["L"])).n))

    return rows, callback


def _finish(rows):
    t = np.array([r[0] for r in rows])
    keep = np.append(np.diff(t) > 0, True)  # stage boundaries repeat a time
    rows = [r for r, k in zip(rows, keep, strict=True) if k]
    return dict(t=np.array([r[0] for r in rows]), kappa=[r[1] for r in rows],
                length=np.array([r[2] for r in rows]), residual=np.array([r[3] for r in rows]),
                counts=np.array([r[4] for r in rows], dtype=int))


def _default_t_final(sc, t_final):
    if t_final is not None:
        return float(t_final)
    return 2.2 if isinstance(sc, FacetScenario) else float(sc.t_final)


def dae_coarsening(scenario=None, *, N=1200, method="bdf2", tol=1e-6, t_final=None):
    """The DAE faceting flow of a scenario, recorded at every accepted step.

    Parameters
    ----------
    scenario : FacetScenario or Scenario, optional
        f:facet's spinodal start (default) via :func:`qsa.paper.run_facet`, or a rounded
        polygon from its splice (``L* = L``).
    N, method, tol
        :func:`qsa.flows.solve_flow`.
    t_final : float, optional
        Default 2.2 for f:facet (after its last event), else the polygon's ``t_final``.

    Returns
    -------
    DAECoarsening
    """
    sc = FacetScenario() if scenario is None else scenario
    if not isinstance(sc, (FacetScenario, Scenario)):
        raise ValueError(f"scenario must be a FacetScenario or a Scenario, got {sc!r}")
    t_final = _default_t_final(sc, t_final)
    rows, callback = _recorder(sc.kstar)
    start = time.process_time()
    splice = None
    if isinstance(sc, FacetScenario):
        run = run_facet(replace(sc, N=int(N), tol=float(tol), method=method), None,
                        t_final=t_final, progress=False, callback=callback)
        message, success = run.message, bool(run.success)
    else:
        eq = sc.splice(FiniteDifference(int(N)))
        L = float(eq.params["L"])
        model = FacetingFlow(sc.alpha, sc.kstar, sc.beta, L)
        first = model.setup(*eq.curve.positions())
        callback(0.0, first.y0, first)
        res = solve_flow(model, eq.curve.positions(), t_final, N=int(N), tol=float(tol),
                         method=method, callback=callback, progress=False)
        message, success = res.message, bool(res.success)
        splice = (np.array(eq.params["positions"]), L)
    cpu = time.process_time() - start
    return DAECoarsening(sc, int(N), method, float(tol), t_final, splice=splice, cpu=cpu,
                         success=success, message=message, **_finish(rows))


def _pair_events(tracks, n0):
    """DAE events as :class:`SequenceEvent` (track indices = fronts at the hand-over)."""
    out, alive = [], n0
    for e in tracks.events:
        a, b = e.fronts
        first = b if (a == 0 and b == n0 - 1) else a  # cyclic order
        second = a if first == b else b
        alive -= 2
        kind = "corner" if tracks.kinds[first] == 1 else "facet"
        out.append(SequenceEvent(float(e.time), alive, (int(first), int(second)), kind))
    return tuple(out)


def _ode_events(sol, order, t0, kinds):
    out, alive = [], sol.n_fronts
    for e in sol.events:
        a, b = (int(order[i]) for i in e.fronts)
        alive -= 2
        out.append(SequenceEvent(float(e.time + t0), alive, (a, b),
                                 "corner" if kinds[a] == 1 else "facet"))
    return tuple(out)


def _state(t, P, kinds, L, kstar):
    """:class:`FrontState` of one row of positions (columns by hand-over index)."""
    live = np.nonzero(np.isfinite(P))[0]
    order = live[np.argsort(P[live] % L)]
    while kinds[order[0]] != 1:
        order = np.roll(order, -1)
    x = P[order] % L
    gaps = np.diff(np.append(x, x[0] + L)) % L
    return FrontState(float(t), tuple(int(i) for i in order),
                      tuple(float(kstar * g) for g in gaps[0::2]),
                      tuple(float(g) for g in gaps[1::2]), float(L))


def _without_drift(P, P0, ref):
    """Positions minus the mean displacement of the fronts ``ref`` since ``P0``."""
    shift = np.nanmean(P[:, ref] - P0[ref], axis=1)
    return P - shift[:, None]


def compare_coarsening(scenario=None, *, N=1200, method="bdf2", tol=1e-6, t_final=None,
                       handover=None, correction="newton", redistribute="project",
                       residual_max=0.3, rtol=1e-6, dae=None):
    """Run the DAE and the front ODE through a whole coarsening and compare the events.

    Parameters
    ----------
    scenario : FacetScenario or Scenario, optional
        f:facet's start (default :class:`FacetScenario`) or a rounded polygon (the DAE
        from its splice, ``L* = L``, hand-over at ``t = 0`` from the splice itself).
    N, method, tol
        The DAE's nodes, stepper and tolerance (:func:`qsa.flows.solve_flow`); the
        default resolves the events to ~1% (f:facet's own run is N = 600, backward
        Euler at ``tol = 1e-4``).
    t_final : float, optional
        Default: the polygon's ``t_final``; for f:facet 2.2 (after the last event,
        t = 1.7).
    handover : float, optional
        Hand-over time for f:facet (default: automatic, see the module docstring).
    correction : {None, "newton"}
    redistribute : {"project", "local", "uniform"}
        The restart after a collision, :meth:`qsa.reduction.FrontODE.integrate`.
    residual_max : float
        Largest ``R_kappa`` of the automatic hand-over.
    rtol : float
        ODE tolerance.
    dae : DAECoarsening, optional
        A recorded DAE run to compare with (then ``scenario``, ``N``, ``method``,
        ``tol`` and ``t_final`` are its own).

    Returns
    -------
    CoarseningComparison

    Raises
    ------
    ValueError
        A scenario of another type, or no state to hand over.
    """
    rec = dae if dae is not None else dae_coarsening(scenario, N=N, method=method, tol=tol,
                                                     t_final=t_final)
    sc, splice, t_final = rec.scenario, rec.splice, rec.t_final
    probe = FrontODE(sc.alpha, sc.kstar, float(rec.length[0]), backend="numpy")
    dc = probe.collision_distance
    if splice is not None:
        i0 = 0
    elif handover is None:
        i0 = _handover_index(rec, sc.kstar, dc, residual_max)
    else:
        i0 = int(np.searchsorted(rec.t, float(handover)))
    if i0 is None or i0 >= rec.t.size:
        raise ValueError("no DAE state to hand over: the fronts never became quasi-steady "
                         f"(R_kappa <= {residual_max:g}) before t_final; pass handover=T")
    t0, L0 = float(rec.t[i0]), float(rec.length[i0])
    L_star = splice[1] if splice is not None else sc.L_star
    ode = FrontODE(sc.alpha, sc.kstar, L0, beta=sc.beta, L_star=L_star,
                   correction=correction)
    if splice is not None:
        p0, mismatch = splice[0], 0.0
        c = detect_fronts(rec.kappa[0], sc.kstar, L0).positions
        d = np.abs((c[None, :] - p0[:, None] + 0.5 * L0) % L0 - 0.5 * L0)
        order = np.argmin(d, axis=1)
    else:
        h = hand_over(ode, rec.kappa[i0], L0)
        p0, order, mismatch = h.positions, h.order, h.mismatch
    tracks = track_fronts(rec.t[i0:], rec.kappa[i0:], sc.kstar, rec.length[i0:])
    kinds = tracks.kinds
    ode.integrate(p0, 1e-9 * t_final, max_collisions=0)  # warm-up (numba kernels load)
    start = time.process_time()
    sol = ode.integrate(p0, t_final - t0, rtol=rtol, max_collisions=4 * p0.size,
                        redistribute=redistribute)
    time_ode = time.process_time() - start
    n0 = p0.size
    P_ode = np.full((sol.t.size, n0), np.nan)
    P_ode[:, order] = sol.positions
    P_dae = tracks.positions
    # same unwrapping as the DAE's first row, then the common drift removed
    P_ode += np.round((P_dae[0] - P_ode[0]) / L0)[None, :] * L0
    ref = np.nonzero(np.isfinite(P_dae[-1]) & np.isfinite(P_ode[-1]))[0]
    if ref.size == 0:
        ref = np.arange(n0)
    P_dae = _without_drift(P_dae, P_dae[0], ref)
    P_ode = _without_drift(P_ode, P_ode[0], ref)
    before = tuple((float(e.t), int(e.after)) for e in coarsening_events(
        rec.t[: i0 + 1], rec.counts[: i0 + 1]).events)
    L_end = float(sol.segments[-1].L[-1])
    return CoarseningComparison(
        sc, rec.N, rec.method, rec.tol, correction, redistribute, t0, int(n0),
        float(rec.residual[i0]), float(mismatch), before, _pair_events(tracks, n0),
        _ode_events(sol, order, t0, kinds), tracks.t, P_dae, sol.t + t0, P_ode,
        _state(rec.t[-1], tracks.positions[-1], kinds, float(rec.length[-1]), sc.kstar),
        _state(t_final, P_ode[-1], kinds, L_end, sc.kstar),
        t_final, rec.cpu, time_ode, int(sol.n_rhs), rec.success, bool(sol.success),
        rec.message, sol.message)


def _handover_index(rec, kstar, dc, residual_max):
    """First step at the peak count or after with ``R_kappa <= residual_max`` and gaps >= 2 d_c."""
    peak = int(np.max(rec.counts))
    first = int(np.nonzero(rec.counts == peak)[0][0])
    for i in range(first, rec.t.size):
        if rec.residual[i] > residual_max or rec.counts[i] < 4:
            continue
        gaps = detect_fronts(rec.kappa[i], kstar, rec.length[i]).gaps()
        if gaps.min() >= 2 * dc:
            return i
    return None
