"""Full-scale runs of the paper's simulations: faceting coarsening, CHA snowflake and folding.

* :func:`run_facet` -- figures f:facet and f:facet_energy: spinodal
  decomposition of a perturbed circle into about 18 fronts that coarsen to 6
  (a rounded equilateral triangle). Per accepted step it records the front
  count (crossings of kappa*/2, :func:`qsa.flows.analysis.count_fronts`), the
  functional residual ``R_kappa`` and the energy; it reports the coarsening
  event times and the final 3-fold symmetry defect.
* :func:`run_cha` -- figures f:Snowflake (rho = 1.3) and f:fold
  (rho = 1.2, 1.3, 1.4 from identical data) with Table T:T1's parameters.
  Per step it checks the polygon for self-intersection and records the
  closest approach of non-neighbouring parts; at the end it finds the paired
  sheets and compares their separation with ``l* sqrt(a^2 + 1/2)``.
* :func:`resolution_check` -- the same scenario at N and 2N over a short
  time, compared at the common nodes.

Every run writes ``<name>.npz`` (arrays) and ``<name>.json`` (summary) to an
output folder, checkpoints through :func:`qsa.flows.solve_flow` (so
``resume=True`` continues an interrupted run) and shows progress. Figures are
drawn by :mod:`qsa.plotting.simulations` (this module imports no matplotlib).

The spinodal phase of the faceting run is integrated with a capped step
(``spinodal_step``): backward Euler damps unstable modes with
``lambda k > 2``, and the position error of the step-doubling control (an
absolute ``tol = 1e-4``) does not see a perturbation of size ``1e-5``, so an
uncapped first phase lets the step size, not the growth rates, select the
spinodal wavenumber.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field

import numpy as np

from qsa._version import __version__
from qsa.flows.analysis import (
    SelfIntersectionMonitor,
    count_fronts,
    curvature_shift_defect,
    facet_lengths,
    front_crossings,
    functional_residual,
    paired_sheets,
    rotation_defect,
)
from qsa.flows.scenarios import CHAScenario, FacetScenario
from qsa.flows.solve import solve_flow
from qsa.io import load_npz, save_npz

__all__ = ["RunOutput", "run_facet", "run_cha", "resolution_check", "coarsening_events",
           "write_output"]


@dataclass
class RunOutput:
    """What a paper run produced.

    Attributes
    ----------
    name : str
        File stem in the output folder.
    summary : dict
        JSON-serialisable numbers (parameters, counters, wall time, targets).
    arrays : dict of str -> ndarray
        Time series and snapshots (written to ``<name>.npz``).
    result : FlowResult or None
        The (last) flow result, with the bound ``system``.
    files : list of str
        Files written.
    """

    name: str
    summary: dict
    arrays: dict
    result: object = None
    files: list = field(default_factory=list)


def write_output(out, name, arrays, summary):
    """Write ``<out>/<name>.npz`` (atomic, no pickle) and ``<out>/<name>.json``; return paths."""
    os.makedirs(out, exist_ok=True)
    npz = save_npz(os.path.join(out, f"{name}.npz"), arrays, summary)
    path = os.path.join(out, f"{name}.json")
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(summary, fh, indent=2, default=_json_default)
        fh.write("\n")
    os.replace(tmp, path)
    return [npz, path]


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


class _Series:
    """Per-step diagnostics recorded by a ``solve_flow`` callback, saved for resuming."""

    def __init__(self, names, path=None, interval=10.0):
        self.names = names
        self.data = {n: [] for n in ("t",) + tuple(names)}
        self.path, self.interval, self._last = path, interval, time.monotonic()

    def append(self, t, **values):
        self.data["t"].append(float(t))
        for n in self.names:
            self.data[n].append(float(values[n]))
        if self.path is not None and time.monotonic() - self._last >= self.interval:
            self.save()

    def save(self):
        if self.path is not None:
            save_npz(self.path, self.arrays(), {"kind": "qsa.run-series"})
            self._last = time.monotonic()

    def load(self, t_max):
        """Restore the saved series up to time ``t_max`` (the resumed checkpoint's time)."""
        if self.path is None or not os.path.isfile(self.path):
            return
        arrays, _ = load_npz(self.path)
        keep = arrays["t"] <= t_max * (1 + 1e-12)
        for n in self.data:
            self.data[n] = [float(v) for v in arrays[n][keep]]

    def arrays(self):
        return {n: np.asarray(v, dtype=float) for n, v in self.data.items()}


def _checkpoint_time(path):
    arrays, _ = load_npz(path)
    return float(arrays["step_t"][-1])


# --------------------------------------------------------------------- facet
def coarsening_events(t, counts):
    """Peak front count and the coarsening events after it.

    Flicker (a count that goes back up while a front pair forms or
    annihilates) is ignored: an event is a time at which the count first falls
    below every count since the peak.

    Returns
    -------
    peak : int
    t_peak : float
    events : list of (t, count_before, count_after)
    """
    t = np.asarray(t, dtype=float)
    counts = np.asarray(counts, dtype=int)
    if counts.size == 0:
        return 0, float("nan"), []
    k = int(np.argmax(counts))
    peak, low, events = int(counts[k]), int(counts[k]), []
    for ti, c in zip(t[k + 1 :], counts[k + 1 :], strict=True):
        if c < low:
            events.append((float(ti), low, int(c)))
            low = int(c)
    return peak, float(t[k]), events


def _facet_state_metrics(system, y, kstar, band):
    u = system.unpack(y)
    x, yy = system.positions(y)
    s, sign = front_crossings(u["kappa"], kstar / 2, band)
    corners, facets = facet_lengths(s, sign, float(u["L"]))
    return {
        "fronts": int(s.size),
        "rotation_defect": rotation_defect(x, yy, 3),
        "curvature_shift_defect": curvature_shift_defect(u["kappa"], 3),
        "corner_turning": [float(c * kstar) for c in corners],
        "facet_lengths": [float(f) for f in facets],
        "R_kappa": functional_residual(u["mu"]),
        "length": float(u["L"]),
    }


def _index_of(times, t):
    return int(np.argmin(np.abs(np.asarray(times) - t)))


def _spread(values):
    v = np.asarray(values, dtype=float)
    return float(np.ptp(v) / np.mean(v)) if v.size else float("nan")


def run_facet(scenario=None, out=None, *, t_final=None, resume=False, progress=None,
              band=None, spinodal_time=1e-4, spinodal_step=2e-6, n_snapshots=40,
              checkpoint_interval=10.0):
    """Faceting coarsening (f:facet, f:facet_energy).

    Parameters
    ----------
    scenario : FacetScenario, optional
        Parameters and initial data (default: the paper's, see
        :class:`~qsa.flows.scenarios.FacetScenario`).
    out : str, optional
        Output folder for ``facet.npz``, ``facet.json`` and the checkpoint.
    t_final : float, optional
        Final time (default ``scenario.t_final``).
    resume : bool
        Continue from ``<out>/facet_checkpoint.npz`` if it exists.
    progress : bool, optional
        Progress bar (default: when stderr is a terminal).
    band : float, optional
        Hysteresis half-width of the front count (default ``0.1 kstar``).
    spinodal_time, spinodal_step : float
        The first phase ``[0, spinodal_time]`` is integrated with steps
        ``<= spinodal_step`` (see the module notes); ``spinodal_time = 0``
        skips it.
    n_snapshots : int
        Log-spaced snapshots kept for the symmetry history (plus the figure
        times).

    Returns
    -------
    RunOutput
        ``summary`` holds the peak front count, the coarsening events, the
        final fronts, the 3-fold symmetry defects, energy monotonicity and the
        wall time; ``arrays`` the per-step series ``t, fronts, R_kappa,
        energy`` and the snapshots.
    """
    sc = FacetScenario() if scenario is None else scenario
    t_final = sc.t_final if t_final is None else float(t_final)
    band = 0.1 * sc.kstar if band is None else float(band)
    model = sc.model()
    wall0 = time.perf_counter()
    ck = None if out is None else os.path.join(out, "facet_checkpoint.npz")
    series = _Series(("fronts", "R_kappa", "energy"),
                     None if out is None else os.path.join(out, "facet_series.npz"))

    def observe(t, y, system):
        u = system.unpack(y)
        series.append(t, fronts=count_fronts(u["kappa"], sc.kstar / 2, band),
                      R_kappa=functional_residual(u["mu"]), energy=system.energy(y))

    snaps = np.union1d(np.geomspace(min(spinodal_time or 1e-4, t_final) / 10, t_final,
                                    n_snapshots), [t for t in sc.figure_times if t <= t_final])
    # the capped phase never takes the whole run (stage 2 needs a positive length)
    t1 = spinodal_time if spinodal_time < t_final else 0.5 * t_final
    stage1 = None
    resuming = bool(resume and ck is not None and os.path.isfile(ck))
    stage1_path = None if out is None else os.path.join(out, "facet_stage1.npz")
    if resuming:
        series.load(_checkpoint_time(ck) + _stage1_time(stage1_path))
        arrays, meta = load_npz(stage1_path) if stage1_path and os.path.isfile(stage1_path) \
            else ({}, {"t1": 0.0})
        t1 = float(meta.get("t1", 0.0))
        stage1 = arrays or None
        start = None
    else:
        start = sc.initial()
        x0, y0 = start
        first = model.setup(x0, y0)
        observe(0.0, first.y0, first)
        if t1 > 0:
            res1 = solve_flow(model, start, t1, N=sc.N, tol=sc.tol, first_step=spinodal_step,
                              max_step=spinodal_step, t_eval=snaps[snaps <= t1],
                              progress=progress, callback=lambda t, y, s: observe(t, y, s))
            if not res1.success:
                return _facet_output(sc, out, series, None, res1, 0.0, t_final, wall0, band,
                                     ck)
            stage1 = {"t": res1.t, "states": res1.states, "t_steps": res1.t_steps,
                      "energy_steps": res1.energy_steps}
            if stage1_path is not None:
                save_npz(stage1_path, stage1, {"kind": "qsa.facet-stage1", "t1": t1})
            start = (res1.x, res1.y)
        else:
            t1 = 0.0
    later = snaps[snaps > t1] - t1
    res2 = solve_flow(model, start, t_final - t1, N=sc.N, tol=sc.tol,
                      t_eval=later if later.size else None, checkpoint=ck,
                      resume=ck if resuming else None, progress=progress,
                      checkpoint_interval=checkpoint_interval,
                      callback=lambda t, y, s: observe(t + t1, y, s))
    series.save()
    return _facet_output(sc, out, series, stage1, res2, t1, t_final, wall0, band, ck)


def _stage1_time(path):
    if path is None or not os.path.isfile(path):
        return 0.0
    return float(load_npz(path)[1].get("t1", 0.0))


def _facet_output(sc, out, series, stage1, res, t1, t_final, wall0, band, ck):
    """Summary and arrays of a facet run; ``stage1`` (dict or None) is the capped-step phase."""
    system = res.system
    # snapshots of both stages on one clock (stage 2 started at t1)
    t_parts, y_parts, n_steps = [res.t + t1], [res.states], res.n_steps
    if stage1 is not None:
        t_parts.insert(0, np.asarray(stage1["t"]))
        y_parts.insert(0, np.asarray(stage1["states"]))
        n_steps += len(stage1["t_steps"]) - 1
    t_snap = np.concatenate(t_parts)
    Y = np.concatenate(y_parts)
    _, first = np.unique(np.round(t_snap, 15), return_index=True)
    t_snap, Y = t_snap[first], Y[first]
    metrics = [_facet_state_metrics(system, y, sc.kstar, band) for y in Y]
    a = series.arrays()
    peak, t_peak, events = coarsening_events(a["t"], a["fronts"])
    dE = np.diff(a["energy"])
    final = metrics[-1]
    wall = time.perf_counter() - wall0
    summary = {
        "scenario": "facet", "version": __version__, "params": sc.params(),
        "t_final": float(t_final), "t_reached": float(a["t"][-1]) if a["t"].size else 0.0,
        "success": bool(res.success), "message": res.message,
        "band": band, "spinodal_time": float(t1),
        "peak_fronts": peak, "t_peak": t_peak,
        "events": [{"t": e[0], "from": e[1], "to": e[2]} for e in events],
        "n_events": len(events),
        "final_fronts": final["fronts"],
        "final_rotation_defect": final["rotation_defect"],
        "final_curvature_shift_defect": final["curvature_shift_defect"],
        "final_corner_turning": final["corner_turning"],
        "final_corner_spread": _spread(final["corner_turning"]),
        "final_facet_spread": _spread(final["facet_lengths"]),
        "final_R_kappa": final["R_kappa"],
        "rotation_defect_at": {f"{t:g}": metrics[_index_of(t_snap, t)]["rotation_defect"]
                               for t in sc.figure_times if t <= t_snap[-1] * (1 + 1e-9)},
        "final_energy": float(a["energy"][-1]) if a["energy"].size else float("nan"),
        "energy_max_increase": float(dE.max()) if dE.size else 0.0,
        "energy_n_increases": int(np.sum(dE > 0)),
        "n_steps": int(n_steps),
        "wall_seconds": wall,
        "checkpoint": ck,
        "paper": {"fronts": "18 -> 6", "events": 6, "symmetry_target": 1e-3,
                  "figure_times": list(sc.figure_times), "R_kappa_between_events": 1e-3},
    }
    arrays = {
        "t": a["t"], "fronts": a["fronts"], "R_kappa": a["R_kappa"], "energy": a["energy"],
        "snap_t": t_snap, "snap_states": Y,
        "snap_rotation_defect": np.array([m["rotation_defect"] for m in metrics]),
        "snap_fronts": np.array([m["fronts"] for m in metrics], dtype=float),
    }
    files = [] if out is None else write_output(out, "facet", arrays, summary)
    return RunOutput("facet", summary, arrays, res, files)


# ----------------------------------------------------------------------- CHA
def run_cha(scenario=None, out=None, *, name=None, t_final=None, N=None, resume=False,
            progress=None, snapshot_times=None, checkpoint_interval=30.0,
            monitor_every=1):
    """The CHA flow from the crenellated start (f:Snowflake, f:fold).

    Parameters
    ----------
    scenario : CHAScenario, optional
        Default: Table T:T1 with rho = 1.3.
    out : str, optional
        Output folder (``<name>.npz``, ``<name>.json``, checkpoint).
    name : str, optional
        File stem (default ``cha_rho<rho>``, plus ``_lstar<l*>`` when l* is
        not Table T1's 0.01).
    t_final, N : optional
        Override the scenario's final time and number of nodes.
    resume : bool
        Continue from ``<out>/<name>_checkpoint.npz`` if it exists.
    snapshot_times : array_like, optional
        Snapshot times (default: the paper's figure times plus 40 log-spaced).
    monitor_every : int
        Check self-intersection every this many accepted steps (1: every step).

    Returns
    -------
    RunOutput
        ``summary`` holds the sheet pairs and their separation against
        ``l* sqrt(a^2 + 1/2)``, the number of stacked nodes, the
        self-intersection report (times of polygon crossings, closest approach)
        and the wall time.
    """
    sc = CHAScenario() if scenario is None else scenario
    t_final = sc.t_final if t_final is None else float(t_final)
    N = sc.N if N is None else int(N)
    if name is None:  # runs with another kernel length do not share checkpoints
        name = f"cha_rho{sc.rho:g}" + ("" if sc.l_star == CHAScenario.l_star
                                        else f"_lstar{sc.l_star:g}")
    model = sc.model()
    wall0 = time.perf_counter()
    ck = None if out is None else os.path.join(out, f"{name}_checkpoint.npz")
    target = sc.pair_separation()
    monitor = SelfIntersectionMonitor(exclude_arc=4 * target)
    series = _Series(("energy", "length", "crossing", "approach"),
                     None if out is None else os.path.join(out, f"{name}_series.npz"))
    count = [0]
    crossing_file = None if out is None else os.path.join(out, f"{name}_crossing.npz")

    def observe(t, y, system):
        count[0] += 1
        if count[0] % monitor_every:
            return
        x, yy = system.positions(y)
        n_before = len(monitor.crossing_times)
        first = monitor.first_crossing
        monitor(t, x, yy)
        if first is None and monitor.first_crossing is not None and crossing_file:
            save_npz(crossing_file, _crossing_arrays(monitor.first_crossing),
                     {"kind": "qsa.first-crossing"})
        series.append(t, energy=system.energy(y), length=system.length(y),
                      crossing=float(len(monitor.crossing_times) > n_before),
                      approach=monitor.approach[-1])

    if snapshot_times is None:
        snapshot_times = np.union1d(np.geomspace(1e-4, t_final, 40),
                                    [t for t in sc.figure_times if 0 < t <= t_final])
    snaps = np.asarray(snapshot_times, dtype=float)
    snaps = snaps[(snaps > 0) & (snaps <= t_final)]
    resuming = bool(resume and ck is not None and os.path.isfile(ck))
    if resuming:
        t_ck = _checkpoint_time(ck)
        series.load(t_ck)
        monitor.first_crossing = _load_crossing(crossing_file, t_ck)
    res = solve_flow(model, sc.initial(N), t_final, N=N, tol=sc.tol, t_eval=snaps,
                     checkpoint=ck, resume=ck if resuming else None, progress=progress,
                     checkpoint_interval=checkpoint_interval, callback=observe)
    series.save()
    system = res.system
    x, y = res.x, res.y
    sheets = paired_sheets(x, y, target)
    a = series.arrays()
    crossing_t = a["t"][a["crossing"] > 0]
    dE = np.diff(res.energy_steps)
    wall = time.perf_counter() - wall0
    approach = a["approach"]
    finite = np.isfinite(approach)
    summary = {
        "scenario": name, "version": __version__, "params": {**sc.params(), "N": N},
        "t_final": float(t_final), "t_reached": float(res.t[-1]),
        "success": bool(res.success), "message": res.message,
        "L0": float(system.L0), "final_length": float(res.length[-1]),
        "target_length": float(sc.rho * system.L0),
        "h_final": float(res.length[-1] / N), "l_star": sc.l_star,
        "sheets": sheets.to_dict(),
        "n_sheet_pairs": sheets.n_pairs,
        "separation": sheets.separation, "separation_target": target,
        "separation_ratio": sheets.separation / target if sheets.n_pairs else None,
        "min_separation_ratio": sheets.to_dict()["min_ratio"],
        "self_intersection": {
            "detected": bool(crossing_t.size),
            "first_time": float(crossing_t[0]) if crossing_t.size else None,
            "last_time": float(crossing_t[-1]) if crossing_t.size else None,
            "n_steps_crossing": int(crossing_t.size),
            "closest_approach": float(np.min(approach[finite])) if finite.any() else None,
            "closest_approach_time": (float(a["t"][finite][np.argmin(approach[finite])])
                                      if finite.any() else None),
            **_first_crossing_summary(monitor.first_crossing),
        },
        "energy_initial": float(res.energy_steps[0]), "energy_final": float(res.energy[-1]),
        "energy_max_increase": float(dE.max()) if dE.size else 0.0,
        "energy_n_increases": int(np.sum(dE > 0)),
        "n_steps": int(res.n_steps), "n_rejected": int(res.n_rejected),
        "n_newton": int(res.n_newton), "wall_seconds": wall, "checkpoint": ck,
        "paper": {"separation": "l* sqrt(a^2 + 1/2)", "within": 0.1,
                  "rho_1.4": "glancing self-intersection in the short-time column"},
    }
    arrays = {
        "t": a["t"], "energy": a["energy"], "length": a["length"], "crossing": a["crossing"],
        "approach": a["approach"], "t_steps": res.t_steps, "energy_steps": res.energy_steps,
        "snap_t": res.t, "snap_x": res.states[:, :N], "snap_y": res.states[:, N : 2 * N],
        "snap_energy": res.energy,
        "x0": system.positions(system.y0)[0], "y0": system.positions(system.y0)[1],
    }
    if monitor.first_crossing is not None:  # the state at the first crossing (figures)
        arrays.update(_crossing_arrays(monitor.first_crossing))
    files = [] if out is None else write_output(out, name, arrays, summary)
    return RunOutput(name, summary, arrays, res, files)


def _crossing_arrays(fc):
    return {"crossing_t": np.array(fc["t"]), "crossing_x": fc["x"], "crossing_y": fc["y"],
            "crossing_points": fc["points"], "crossing_segments": fc["segments"],
            "crossing_arc_gap": fc["arc_gap"]}


def _load_crossing(path, t_max):
    """The first-crossing record saved before the checkpoint at ``t_max`` (or None)."""
    if path is None or not os.path.isfile(path):
        return None
    a, _ = load_npz(path)
    if float(a["crossing_t"]) > t_max * (1 + 1e-12):
        return None
    return {"t": float(a["crossing_t"]), "x": a["crossing_x"], "y": a["crossing_y"],
            "points": a["crossing_points"], "segments": a["crossing_segments"],
            "arc_gap": a["crossing_arc_gap"]}


def _first_crossing_summary(fc):
    """JSON part of the self-intersection report: where the first crossing was."""
    if fc is None:
        return {"first_crossing_points": None, "first_crossing_arc_gap": None}
    return {"first_crossing_points": fc["points"].tolist(),
            "first_crossing_arc_gap": fc["arc_gap"].tolist()}


def resolution_check(scenario=None, N=None, t_short=2e-3, *, progress=None):
    """Run ``scenario`` at ``N`` and ``2N`` to ``t_short``; compare positions at common nodes.

    Node ``j`` of the N run and node ``2j`` of the 2N run sit at the same
    parameter ``s = j/N`` (equal chords, same first node).

    Returns
    -------
    dict
        ``max_difference`` (max over nodes of the position difference),
        its ratio to ``l*`` (CHA), and per run (N, 2N) ``wall``, ``steps``,
        ``success``.
    """
    sc = CHAScenario() if scenario is None else scenario
    N = sc.N if N is None else int(N)
    out = {"N": N, "t_short": float(t_short), "wall": [], "steps": [], "success": []}
    pos = {}
    for n in (N, 2 * N):
        w0 = time.perf_counter()
        res = solve_flow(sc.model(), sc.initial(n), t_short, N=n, tol=sc.tol,
                         progress=progress)
        out["wall"].append(time.perf_counter() - w0)
        out["steps"].append(int(res.n_steps))
        out["success"].append(bool(res.success))
        pos[n] = (res.x, res.y)
    d = np.hypot(pos[N][0] - pos[2 * N][0][::2], pos[N][1] - pos[2 * N][1][::2])
    out["max_difference"] = float(d.max())
    scale = getattr(sc, "l_star", None)
    if scale:
        out["max_difference_over_l_star"] = float(d.max() / scale)
    return out
