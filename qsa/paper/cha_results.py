"""Results of the paper's CHA simulations (the snowflake, folding, resolution check).

Frozen, like the faceting results of :mod:`qsa.paper.results` (which re-exports these):
the time series and snapshots as arrays, the flow result, the derived numbers (paired
sheets, self-intersection report) as properties, ``summary()`` / ``arrays()`` /
``to_json()``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa._version import __version__
from qsa.flows.analysis import SheetPairs
from qsa.paper._files import _Summarised
from qsa.paper.scenarios import CHAScenario

__all__ = ["Crossing", "SelfIntersectionReport", "CHARun", "FoldingRun", "ResolutionCheck"]


@dataclass(frozen=True, eq=False)
class Crossing:
    """The state at a polygon self-intersection.

    Attributes
    ----------
    t : float
    x, y : ndarray, shape (N,)
        The nodes.
    points : ndarray, shape (K, 2)
        Crossing points.
    segments : ndarray, shape (K, 2)
        Indices of the crossing segment pairs.
    arc_gap : ndarray, shape (K,)
        Arc length between the crossing segments along the curve.
    """

    t: float
    x: np.ndarray
    y: np.ndarray
    points: np.ndarray
    segments: np.ndarray
    arc_gap: np.ndarray

    @classmethod
    def from_record(cls, fc):
        """From :attr:`qsa.flows.analysis.SelfIntersectionMonitor.first_crossing`."""
        return cls(float(fc["t"]), fc["x"], fc["y"], fc["points"], fc["segments"],
                   fc["arc_gap"])

    def arrays(self):
        """``crossing_t``, ``crossing_x``, ... (the ``.npz`` entries)."""
        return {"crossing_t": np.array(self.t), "crossing_x": self.x, "crossing_y": self.y,
                "crossing_points": self.points, "crossing_segments": self.segments,
                "crossing_arc_gap": self.arc_gap}

    @classmethod
    def from_arrays(cls, a):
        return cls(float(a["crossing_t"]), a["crossing_x"], a["crossing_y"],
                   a["crossing_points"], a["crossing_segments"], a["crossing_arc_gap"])


@dataclass(frozen=True, eq=False)
class SelfIntersectionReport:
    """When and where a run's polygon crossed itself, and its closest approach.

    ``closest_approach`` is the smallest distance between parts of the curve more
    than four pair separations apart along it (None if never measured).
    """

    detected: bool
    first_time: float | None
    last_time: float | None
    n_steps_crossing: int
    closest_approach: float | None
    closest_approach_time: float | None
    first_crossing: Crossing | None

    def summary(self):
        fc = self.first_crossing
        return {
            "detected": self.detected, "first_time": self.first_time,
            "last_time": self.last_time, "n_steps_crossing": self.n_steps_crossing,
            "closest_approach": self.closest_approach,
            "closest_approach_time": self.closest_approach_time,
            "first_crossing_points": None if fc is None else fc.points.tolist(),
            "first_crossing_arc_gap": None if fc is None else fc.arc_gap.tolist(),
        }


@dataclass(frozen=True, eq=False)
class CHARun(_Summarised):
    """The CHA flow from the crenellated start (:func:`qsa.paper.run_cha`).

    Attributes
    ----------
    name : str
        File stem (``cha_rho<rho>[_lstar<l*>]``).
    scenario : CHAScenario
    N : int
    t_final : float
    success : bool
    message : str
    L0 : float
        Initial length.
    final_length : float
    sheets : SheetPairs
        Paired sheets of the final state.
    t, energy, length, crossing, approach : ndarray, shape (n,)
        Per monitored step: time, energy, length, 1 where the polygon crossed
        itself, closest approach.
    t_steps, energy_steps : ndarray
        Energy at every accepted step.
    snap_t : ndarray, shape (m,)
    snap_x, snap_y : ndarray, shape (m, N)
    snap_energy : ndarray, shape (m,)
    x0, y0 : ndarray, shape (N,)
        Initial nodes.
    first_crossing : Crossing or None
    n_steps, n_rejected, n_newton : int
    wall_seconds : float
    checkpoint : str or None
    result : FlowResult
    files : tuple of str
    """

    name: str
    scenario: CHAScenario
    N: int
    t_final: float
    success: bool
    message: str
    L0: float
    final_length: float
    sheets: SheetPairs
    t: np.ndarray
    energy: np.ndarray
    length: np.ndarray
    crossing: np.ndarray
    approach: np.ndarray
    t_steps: np.ndarray
    energy_steps: np.ndarray
    snap_t: np.ndarray
    snap_x: np.ndarray
    snap_y: np.ndarray
    snap_energy: np.ndarray
    x0: np.ndarray
    y0: np.ndarray
    first_crossing: Crossing | None
    n_steps: int
    n_rejected: int
    n_newton: int
    wall_seconds: float
    checkpoint: str | None = None
    result: object = None
    files: tuple = ()

    @property
    def rho(self):
        return self.scenario.rho

    @property
    def t_reached(self):
        return float(self.snap_t[-1])

    @property
    def target_length(self):
        """``rho L0``, the length the penalty favours."""
        return float(self.scenario.rho * self.L0)

    @property
    def separation_target(self):
        """``l* sqrt(a^2 + 1/2)``."""
        return self.scenario.pair_separation()

    @property
    def n_sheet_pairs(self):
        return self.sheets.n_pairs

    @property
    def separation(self):
        return self.sheets.separation

    @property
    def separation_ratio(self):
        """Median separation / target (None without pairs)."""
        return self.sheets.separation / self.separation_target if self.sheets.n_pairs else None

    @property
    def min_separation_ratio(self):
        """Smallest closest-point separation / target (None without pairs)."""
        return self.sheets.to_dict()["min_ratio"]

    @property
    def energy_initial(self):
        return float(self.energy_steps[0])

    @property
    def energy_final(self):
        return float(self.snap_energy[-1])

    @property
    def energy_max_increase(self):
        dE = np.diff(self.energy_steps)
        return float(dE.max()) if dE.size else 0.0

    @property
    def energy_n_increases(self):
        return int(np.sum(np.diff(self.energy_steps) > 0))

    @property
    def self_intersection(self):
        """:class:`SelfIntersectionReport` of the monitored steps."""
        crossing_t = self.t[self.crossing > 0]
        finite = np.isfinite(self.approach)
        a = self.approach[finite]
        return SelfIntersectionReport(
            detected=bool(crossing_t.size),
            first_time=float(crossing_t[0]) if crossing_t.size else None,
            last_time=float(crossing_t[-1]) if crossing_t.size else None,
            n_steps_crossing=int(crossing_t.size),
            closest_approach=float(np.min(a)) if a.size else None,
            closest_approach_time=float(self.t[finite][np.argmin(a)]) if a.size else None,
            first_crossing=self.first_crossing)

    def summary(self):
        """The JSON summary (``<name>.json``, ``qsa reproduce snowflake --json``)."""
        sc = self.scenario
        return {
            "scenario": self.name, "version": __version__, "params": {**sc.params(), "N": self.N},
            "t_final": float(self.t_final), "t_reached": self.t_reached,
            "success": bool(self.success), "message": self.message,
            "L0": float(self.L0), "final_length": float(self.final_length),
            "target_length": self.target_length,
            "h_final": float(self.final_length / self.N), "l_star": sc.l_star,
            "sheets": self.sheets.to_dict(),
            "n_sheet_pairs": self.n_sheet_pairs,
            "separation": self.separation, "separation_target": self.separation_target,
            "separation_ratio": self.separation_ratio,
            "min_separation_ratio": self.min_separation_ratio,
            "self_intersection": self.self_intersection.summary(),
            "energy_initial": self.energy_initial, "energy_final": self.energy_final,
            "energy_max_increase": self.energy_max_increase,
            "energy_n_increases": self.energy_n_increases,
            "n_steps": int(self.n_steps), "n_rejected": int(self.n_rejected),
            "n_newton": int(self.n_newton), "wall_seconds": self.wall_seconds,
            "checkpoint": self.checkpoint,
            "paper": {"separation": "l* sqrt(a^2 + 1/2)", "within": 0.1,
                      "rho_1.4": "glancing self-intersection in the short-time column"},
        }

    def arrays(self):
        """The arrays of ``<name>.npz`` (with the first crossing's state, if any)."""
        out = {
            "t": self.t, "energy": self.energy, "length": self.length,
            "crossing": self.crossing, "approach": self.approach, "t_steps": self.t_steps,
            "energy_steps": self.energy_steps, "snap_t": self.snap_t, "snap_x": self.snap_x,
            "snap_y": self.snap_y, "snap_energy": self.snap_energy, "x0": self.x0,
            "y0": self.y0,
        }
        if self.first_crossing is not None:
            out.update(self.first_crossing.arrays())
        return out


def _within(ratio, tol=0.1):
    return ratio is not None and abs(ratio - 1) <= tol


@dataclass(frozen=True, eq=False)
class FoldingRun(_Summarised):
    """CHA runs from identical data for several ``rho`` (:func:`qsa.paper.run_folding`).

    ``runs`` are sorted by ``rho``; the properties compare them with the paper
    (more folds for larger rho, separation within 10% of ``l* sqrt(a^2 + 1/2)``).
    """

    runs: tuple

    @property
    def rho(self):
        return [r.rho for r in self.runs]

    @property
    def n_sheet_pairs(self):
        return [r.n_sheet_pairs for r in self.runs]

    @property
    def separation_ratio(self):
        return [r.separation_ratio for r in self.runs]

    @property
    def min_separation_ratio(self):
        return [r.min_separation_ratio for r in self.runs]

    @property
    def more_folds_for_larger_rho(self):
        p = self.n_sheet_pairs
        return all(b >= a for a, b in zip(p, p[1:], strict=False)) and p[-1] > p[0]

    @property
    def success(self):
        return all(r.success for r in self.runs)

    def summary(self):
        """The JSON summary (``folding.json``, ``qsa reproduce folding --json``)."""
        return {
            "rho": self.rho,
            "n_sheet_pairs": self.n_sheet_pairs,
            "separation_ratio": self.separation_ratio,
            "min_separation_ratio": self.min_separation_ratio,
            "all_within_10_percent": all(_within(r) for r in self.separation_ratio),
            "all_closest_within_10_percent": all(_within(r) for r in self.min_separation_ratio),
            "more_folds_for_larger_rho": self.more_folds_for_larger_rho,
            "self_intersection": {f"{r.rho:g}": r.self_intersection.detected
                                  for r in self.runs},
            "wall_seconds": [r.wall_seconds for r in self.runs],
            "runs": [r.summary() for r in self.runs],
        }


@dataclass(frozen=True)
class ResolutionCheck(_Summarised):
    """A scenario at ``N`` and ``2N`` to ``t_short`` (:func:`qsa.paper.resolution_check`).

    ``wall``, ``steps``, ``success`` are per run (N, 2N); ``max_difference`` the
    largest node position difference at common nodes, ``max_difference_over_l_star``
    its ratio to the kernel length (None for scenarios without one).
    """

    N: int
    t_short: float
    wall: tuple
    steps: tuple
    success: tuple
    max_difference: float
    max_difference_over_l_star: float | None = None

    def summary(self):
        out = {"N": self.N, "t_short": self.t_short, "wall": list(self.wall),
               "steps": list(self.steps), "success": list(self.success),
               "max_difference": self.max_difference}
        if self.max_difference_over_l_star is not None:
            out["max_difference_over_l_star"] = self.max_difference_over_l_star
        return out
