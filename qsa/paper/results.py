"""Results of the paper's simulations (:mod:`qsa.paper.runs`): frozen, with named fields.

Each result keeps the time series and snapshots of its run as arrays and the
flow result (``result``, with the bound DAE ``system``); the derived numbers
(coarsening events, symmetry defects, paired sheets, self-intersection report)
are properties. ``summary()`` gives the JSON-ready dictionary that
``qsa reproduce ... --json`` prints and ``<name>.json`` stores, ``arrays()`` the
arrays of ``<name>.npz``, ``to_json()`` the summary as text. The faceting results are
here, the CHA ones in :mod:`qsa.paper.cha_results` (re-exported).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from qsa._version import __version__
from qsa.paper._files import _Summarised
from qsa.paper.cha_results import (
    CHARun,
    Crossing,
    FoldingRun,
    ResolutionCheck,
    SelfIntersectionReport,
)
from qsa.paper.scenarios import FacetScenario

__all__ = ["CoarseningEvent", "Coarsening", "coarsening_events", "FigureRow", "Plateau",
           "FacetState", "FacetRun",
           "Crossing", "SelfIntersectionReport", "CHARun", "FoldingRun", "ResolutionCheck"]


class CoarseningEvent(NamedTuple):
    """The front count falls from ``before`` to ``after`` at time ``t``."""

    t: float
    before: int
    after: int


class Coarsening(NamedTuple):
    """Peak front count, its time and the coarsening events after it."""

    peak: int
    t_peak: float
    events: list


def coarsening_events(t, counts):
    """Peak front count and the coarsening events after it.

    Flicker (a count that goes back up while a front pair forms or
    annihilates) is ignored: an event is a time at which the count first falls
    below every count since the peak.

    Returns
    -------
    Coarsening
        ``peak``, ``t_peak`` and ``events`` (list of :class:`CoarseningEvent`).

    Examples
    --------
    >>> c = coarsening_events([0, 1, 2, 3, 4], [0, 6, 4, 6, 2])
    >>> c.peak, [(e.t, e.before, e.after) for e in c.events]
    (6, [(2.0, 6, 4), (4.0, 4, 2)])
    """
    t = np.asarray(t, dtype=float)
    counts = np.asarray(counts, dtype=int)
    if counts.size == 0:
        return Coarsening(0, float("nan"), [])
    k = int(np.argmax(counts))
    peak, low, events = int(counts[k]), int(counts[k]), []
    for ti, c in zip(t[k + 1 :], counts[k + 1 :], strict=True):
        if c < low:
            events.append(CoarseningEvent(float(ti), low, int(c)))
            low = int(c)
    return Coarsening(peak, float(t[k]), events)


class FigureRow(NamedTuple):
    """qsa's values at one of the paper's figure times, next to the paper's.

    ``paper_t`` is the time printed in the paper (its clock), ``t`` the physical time
    (``paper_clock`` times it); ``fronts``, ``R_kappa``, ``energy`` qsa's at the step
    nearest ``t``; ``paper_fronts`` and ``paper_R_kappa`` what the paper states there
    (None where its text gives nothing).
    """

    paper_t: float
    t: float
    fronts: int
    R_kappa: float
    energy: float
    paper_fronts: int | None
    paper_R_kappa: float | None


class Plateau(NamedTuple):
    """A stretch between coarsening events: its times, front count and residual.

    ``R_kappa`` is the median of the functional residual over the middle 60% of the
    stretch (away from the events' excursions), ``R_kappa_min`` its minimum there.
    """

    t_start: float
    t_end: float
    fronts: int
    R_kappa: float
    R_kappa_min: float


@dataclass(frozen=True)
class FacetState:
    """Fronts and symmetry of one snapshot of the faceting run.

    ``corner_turning`` is each corner's turning angle (``kstar`` times its
    length), ``facet_lengths`` the facets' arc lengths; the defects measure the
    distance from 3-fold symmetry (:func:`qsa.flows.analysis.rotation_defect`,
    :func:`~qsa.flows.analysis.curvature_shift_defect`); ``R_kappa`` is the
    functional residual.
    """

    fronts: int
    rotation_defect: float
    curvature_shift_defect: float
    corner_turning: tuple
    facet_lengths: tuple
    R_kappa: float
    length: float

    @property
    def corner_spread(self):
        """``(max - min) / mean`` of the corner turnings (0 for a regular polygon)."""
        return _spread(self.corner_turning)

    @property
    def facet_spread(self):
        """``(max - min) / mean`` of the facet lengths."""
        return _spread(self.facet_lengths)


def _spread(values):
    v = np.asarray(values, dtype=float)
    return float(np.ptp(v) / np.mean(v)) if v.size else float("nan")


def _index_of(times, t):
    return int(np.argmin(np.abs(np.asarray(times) - t)))


@dataclass(frozen=True, eq=False)
class FacetRun(_Summarised):
    """Faceting coarsening (:func:`qsa.paper.run_facet`).

    Attributes
    ----------
    scenario : FacetScenario
    t_final : float
        Requested final time.
    success : bool
    message : str
    band : float
        Hysteresis half-width of the front count.
    spinodal_time : float
        End of the capped-step first phase (0: none).
    t, fronts, R_kappa, energy : ndarray, shape (n,)
        Per accepted step: time, front count, functional residual, energy.
    snap_t : ndarray, shape (m,)
    snap_states : ndarray, shape (m, size)
        Snapshots of the DAE state (both phases on one clock).
    snapshots : tuple of FacetState
        Fronts and symmetry of each snapshot.
    n_steps : int
    wall_seconds : float
    checkpoint : str or None
    result : FlowResult
        The last phase's flow result (with its ``system``).
    files : tuple of str
        Files written.
    """

    scenario: FacetScenario
    t_final: float
    success: bool
    message: str
    band: float
    spinodal_time: float
    t: np.ndarray
    fronts: np.ndarray
    R_kappa: np.ndarray
    energy: np.ndarray
    snap_t: np.ndarray
    snap_states: np.ndarray
    snapshots: tuple
    n_steps: int
    wall_seconds: float
    checkpoint: str | None = None
    result: object = None
    files: tuple = ()

    name = "facet"

    @property
    def t_reached(self):
        return float(self.t[-1]) if self.t.size else 0.0

    @property
    def coarsening(self):
        """:class:`Coarsening` of the per-step front count."""
        return coarsening_events(self.t, self.fronts)

    @property
    def final(self):
        """:class:`FacetState` of the last snapshot."""
        return self.snapshots[-1]

    @property
    def rotation_defect_at(self):
        """``{f"{t:g}": defect}`` at the snapshots nearest the (physical) figure times reached."""
        return {f"{t:g}": self.snapshots[_index_of(self.snap_t, t)].rotation_defect
                for t in self.scenario.physical_figure_times
                if t <= self.snap_t[-1] * (1 + 1e-9)}

    @property
    def figure_rows(self):
        """:class:`FigureRow` at each of the paper's figure times reached.

        The paper's text gives 18 fronts at its first panel (t = 2.2e-4), the
        triangle (6 fronts) at its last (t = 2) and ``R_kappa ~ 1e-3`` from
        t = 2e-4 on, between the events' excursions.
        """
        sc, rows = self.scenario, []
        times = sc.figure_times
        for k, (tp, t) in enumerate(zip(times, sc.physical_figure_times, strict=True)):
            if t > self.t_reached * (1 + 1e-9):
                continue
            i = _index_of(self.t, t)
            paper_fronts = 18 if k == 0 else 6 if k == len(times) - 1 else None
            rows.append(FigureRow(float(tp), float(t), int(self.fronts[i]),
                                  float(self.R_kappa[i]), float(self.energy[i]),
                                  paper_fronts, 1e-3 if tp >= 2e-4 else None))
        return rows

    @property
    def plateaus(self):
        """:class:`Plateau` between successive events (from the peak front count on)."""
        c = self.coarsening
        if not np.isfinite(c.t_peak):
            return []
        ends = [c.t_peak] + [e.t for e in c.events] + [self.t_reached]
        out = []
        for a, b in zip(ends[:-1], ends[1:], strict=True):
            m = (self.t > a + 0.2 * (b - a)) & (self.t < b - 0.2 * (b - a))
            if np.any(m):
                out.append(Plateau(float(a), float(b), int(np.median(self.fronts[m])),
                                   float(np.median(self.R_kappa[m])),
                                   float(np.min(self.R_kappa[m]))))
        return out

    @property
    def final_energy(self):
        return float(self.energy[-1]) if self.energy.size else float("nan")

    @property
    def energy_max_increase(self):
        dE = np.diff(self.energy)
        return float(dE.max()) if dE.size else 0.0

    @property
    def energy_n_increases(self):
        return int(np.sum(np.diff(self.energy) > 0))

    def summary(self):
        """The JSON summary (``facet.json``, ``qsa reproduce facet --json``)."""
        sc, final, c = self.scenario, self.final, self.coarsening
        return {
            "scenario": "facet", "version": __version__, "params": sc.params(),
            "t_final": float(self.t_final), "t_reached": self.t_reached,
            "success": bool(self.success), "message": self.message,
            "band": self.band, "spinodal_time": float(self.spinodal_time),
            "peak_fronts": c.peak, "t_peak": c.t_peak,
            "events": [{"t": e.t, "from": e.before, "to": e.after} for e in c.events],
            "n_events": len(c.events),
            "final_fronts": final.fronts,
            "final_rotation_defect": final.rotation_defect,
            "final_curvature_shift_defect": final.curvature_shift_defect,
            "final_corner_turning": list(final.corner_turning),
            "final_corner_spread": final.corner_spread,
            "final_facet_spread": final.facet_spread,
            "final_R_kappa": final.R_kappa,
            "rotation_defect_at": self.rotation_defect_at,
            "figure_rows": [r._asdict() for r in self.figure_rows],
            "plateaus": [p._asdict() for p in self.plateaus],
            "final_energy": self.final_energy,
            "energy_max_increase": self.energy_max_increase,
            "energy_n_increases": self.energy_n_increases,
            "n_steps": int(self.n_steps),
            "wall_seconds": self.wall_seconds,
            "checkpoint": self.checkpoint,
            "paper": {"fronts": "18 -> 6", "events": 6, "symmetry_target": 1e-3,
                      "figure_times": list(sc.figure_times),
                      "physical_figure_times": list(sc.physical_figure_times),
                      "R_kappa_between_events": 1e-3},
        }

    def arrays(self):
        """The arrays of ``facet.npz``."""
        return {
            "t": self.t, "fronts": self.fronts, "R_kappa": self.R_kappa, "energy": self.energy,
            "snap_t": self.snap_t, "snap_states": self.snap_states,
            "snap_rotation_defect": np.array([m.rotation_defect for m in self.snapshots]),
            "snap_fronts": np.array([m.fronts for m in self.snapshots], dtype=float),
            **self._snapshot_nodes(),
        }

    def _snapshot_nodes(self):
        """``snap_x``, ``snap_y`` (m, N): the nodes of each snapshot (empty without a system)."""
        system = getattr(self.result, "system", None)
        if system is None or not len(self.snap_states):
            return {}
        xy = [system.positions(y) for y in self.snap_states]
        return {"snap_x": np.array([p[0] for p in xy]), "snap_y": np.array([p[1] for p in xy])}
