"""Runs of the paper's simulations: faceting coarsening, CHA snowflake and folding.

* :func:`run_facet` -- figures f:facet and f:facet_energy: spinodal
  decomposition of a perturbed circle into about 18 fronts that coarsen to 6
  (a rounded equilateral triangle). Per accepted step it records the front
  count (crossings of kappa*/2, :func:`qsa.flows.analysis.count_fronts`), the
  functional residual ``R_kappa`` and the energy; it reports the coarsening
  event times and the final 3-fold symmetry defect.
* :func:`run_cha` -- figures f:Snowflake (rho = 1.3) and f:fold
  (rho = 1.2, 1.3, 1.4 from identical data, :func:`run_folding`) with Table
  T:T1's parameters. Per step it checks the polygon for self-intersection and
  records the closest approach of non-neighbouring parts; at the end it finds
  the paired sheets and compares their separation with ``l* sqrt(a^2 + 1/2)``.
* :func:`resolution_check` -- the same scenario at N and 2N over a short
  time, compared at the common nodes.

Every run returns a frozen result (:mod:`qsa.paper.results`); given an output
folder it writes ``<name>.npz`` (arrays) and ``<name>.json`` (summary),
checkpoints through :func:`qsa.flows.solve_flow` (so ``resume=True``
continues an interrupted run) and shows progress. Figures are drawn by
:mod:`qsa.plotting.simulations` (this module imports no matplotlib).

The spinodal phase of the faceting run is integrated with a capped step
(``spinodal_step``): backward Euler damps unstable modes with
``lambda k > 2``, and the position error of the step-doubling control (an
absolute ``tol = 1e-4``) does not see a perturbation of size ``1e-5``, so an
uncapped first phase lets the step size, not the growth rates, select the
spinodal wavenumber.
"""

from __future__ import annotations

import os
import time
from dataclasses import asdict, replace

import numpy as np

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
from qsa.flows.solve import solve_flow
from qsa.npz import load_npz, save_npz
from qsa.paper._files import Series, checkpoint_nodes, checkpoint_time, write_output
from qsa.paper.results import (
    CHARun,
    Crossing,
    FacetRun,
    FacetState,
    FoldingRun,
    ResolutionCheck,
    coarsening_events,
)
from qsa.paper.scenarios import CHAScenario, FacetScenario

__all__ = ["run_facet", "run_cha", "cha_run_name", "run_folding", "resolution_check",
           "coarsening_events",
           "write_output"]


# --------------------------------------------------------------------- facet
def _facet_state(system, y, kstar, band):
    u = system.unpack(y)
    x, yy = system.positions(y)
    s, sign = front_crossings(u["kappa"], kstar / 2, band)
    corners, facets = facet_lengths(s, sign, float(u["L"]))
    return FacetState(
        fronts=int(s.size),
        rotation_defect=rotation_defect(x, yy, 3),
        curvature_shift_defect=curvature_shift_defect(u["kappa"], 3),
        corner_turning=tuple(float(c * kstar) for c in corners),
        facet_lengths=tuple(float(f) for f in facets),
        R_kappa=functional_residual(u["mu"]),
        length=float(u["L"]),
    )


def run_facet(scenario=None, out=None, *, t_final=None, resume=False, progress=None,
              band=None, spinodal_time=None, spinodal_step=2e-6, n_snapshots=40,
              checkpoint_interval=10.0, callback=None):
    """Faceting coarsening (f:facet, f:facet_energy).

    Parameters
    ----------
    scenario : FacetScenario, optional
        Parameters and initial data (default: the paper's, see
        :class:`~qsa.paper.scenarios.FacetScenario`).
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
        The first phase ``[0, spinodal_time]`` (default the scenario's) is
        integrated with steps ``<= spinodal_step`` (see the module notes);
        ``spinodal_time = 0`` skips it.
    n_snapshots : int
        Log-spaced snapshots kept for the symmetry history (plus the figure
        times).
    callback : callable, optional
        ``callback(t, y, system)`` after every accepted step of both phases (``t``
        on the run's clock), e.g. to record the states.

    Returns
    -------
    FacetRun
        The per-step series ``t, fronts, R_kappa, energy``, the snapshots and
        their fronts and symmetry; ``coarsening`` (peak front count, events),
        ``final`` (the last snapshot's fronts and 3-fold symmetry defects),
        energy monotonicity and the wall time.
    """
    sc = FacetScenario() if scenario is None else scenario
    t_final = sc.t_final if t_final is None else float(t_final)
    band = 0.1 * sc.kstar if band is None else float(band)
    spinodal_time = sc.spinodal_time if spinodal_time is None else float(spinodal_time)
    model = sc.model()
    wall0 = time.perf_counter()
    ck = None if out is None else os.path.join(out, "facet_checkpoint.npz")
    series = Series(("fronts", "R_kappa", "energy"),
                    None if out is None else os.path.join(out, "facet_series.npz"))

    def observe(t, y, system):
        u = system.unpack(y)
        series.append(t, fronts=count_fronts(u["kappa"], sc.kstar / 2, band),
                      R_kappa=functional_residual(u["mu"]), energy=system.energy(y))
        if callback is not None:
            callback(t, y, system)

    snaps = np.union1d(np.geomspace(min(spinodal_time or 1e-4, t_final) / 10, t_final,
                                    n_snapshots),
                         [t for t in sc.physical_figure_times if t <= t_final])
    # the capped phase never takes the whole run (stage 2 needs a positive length)
    t1 = spinodal_time if spinodal_time < t_final else 0.5 * t_final
    stage1 = None
    resuming = bool(resume and ck is not None and os.path.isfile(ck))
    stage1_path = None if out is None else os.path.join(out, "facet_stage1.npz")
    if resuming:
        series.load(checkpoint_time(ck) + _stage1_time(stage1_path))
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
            res1 = solve_flow(model, start, t1, N=sc.N, tol=sc.tol, method=sc.method,
                              first_step=spinodal_step,
                              max_step=spinodal_step, t_eval=snaps[snaps <= t1],
                              progress=progress, callback=lambda t, y, s: observe(t, y, s))
            if not res1.success:
                return _facet_run(sc, out, series, None, res1, 0.0, t_final, wall0, band, ck)
            stage1 = {"t": res1.t, "states": res1.states, "t_steps": res1.t_steps,
                      "energy_steps": res1.energy_steps}
            if stage1_path is not None:
                save_npz(stage1_path, stage1, {"kind": "qsa.facet-stage1", "t1": t1})
            start = (res1.x, res1.y)
        else:
            t1 = 0.0
    later = snaps[snaps > t1] - t1
    try:
        res2 = solve_flow(model, start, t_final - t1, N=sc.N, tol=sc.tol, method=sc.method,
                          t_eval=later if later.size else None, checkpoint=ck,
                          resume=ck if resuming else None, progress=progress,
                          checkpoint_interval=checkpoint_interval,
                          callback=lambda t, y, s: observe(t + t1, y, s))
    finally:  # also on Ctrl-C, so that a resumed run finds the series up to its checkpoint
        series.save()
    return _facet_run(sc, out, series, stage1, res2, t1, t_final, wall0, band, ck)


def _stage1_time(path):
    if path is None or not os.path.isfile(path):
        return 0.0
    return float(load_npz(path)[1].get("t1", 0.0))


def _facet_run(sc, out, series, stage1, res, t1, t_final, wall0, band, ck):
    """The :class:`FacetRun`; ``stage1`` (dict of arrays or None) is the capped-step phase."""
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
    a = series.arrays()
    run = FacetRun(
        scenario=sc, t_final=float(t_final), success=bool(res.success), message=res.message,
        band=band, spinodal_time=float(t1), t=a["t"], fronts=a["fronts"],
        R_kappa=a["R_kappa"], energy=a["energy"], snap_t=t_snap, snap_states=Y,
        snapshots=tuple(_facet_state(system, y, sc.kstar, band) for y in Y),
        n_steps=int(n_steps), wall_seconds=time.perf_counter() - wall0, checkpoint=ck,
        result=res)
    if out is None:
        return run
    return replace(run, files=tuple(write_output(out, "facet", run.arrays(), run.summary())))


# ----------------------------------------------------------------------- CHA
def cha_run_name(scenario):
    """File stem of a CHA run: ``cha_rho1.3`` (``_lstar0.1`` added for another kernel length,
    so that runs with another l* do not share checkpoints)."""
    return f"cha_rho{scenario.rho:g}" + ("" if scenario.l_star == CHAScenario.l_star
                                         else f"_lstar{scenario.l_star:g}")


def run_cha(scenario=None, out=None, *, name=None, t_final=None, N=None, resume=False,
            progress=None, snapshot_times=None, checkpoint_interval=30.0,
            monitor_every=1):
    """The CHA flow from the crenellated start (f:Snowflake, f:fold).

    Parameters
    ----------
    scenario : CHAScenario, optional
        Default: Table T:T1 (l* = 0.1, N = 600) with rho = 1.3.
    out : str, optional
        Output folder (``<name>.npz``, ``<name>.json``, checkpoint).
    name : str, optional
        File stem (default ``cha_rho<rho>``, plus ``_lstar<l*>`` when l* is
        not the default 0.1).
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
    CHARun
        The sheet pairs (``sheets``) and their separation against
        ``l* sqrt(a^2 + 1/2)``, the self-intersection report (times of polygon
        crossings, where the first one happened, closest approach), the series,
        snapshots and the wall time.
    """
    sc = CHAScenario() if scenario is None else scenario
    t_final = sc.t_final if t_final is None else float(t_final)
    N_given = N
    N = sc.N if N is None else int(N)
    if name is None:
        name = cha_run_name(sc)
    model = sc.model()
    wall0 = time.perf_counter()
    ck = None if out is None else os.path.join(out, f"{name}_checkpoint.npz")
    target = sc.pair_separation()
    monitor = SelfIntersectionMonitor(exclude_arc=4 * target)
    series = Series(("energy", "length", "crossing", "approach"),
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
            save_npz(crossing_file, Crossing.from_record(monitor.first_crossing).arrays(),
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
        if N_given is None:  # a resumed run keeps its grid
            N = checkpoint_nodes(ck)
        t_ck = checkpoint_time(ck)
        series.load(t_ck)
        saved = _load_crossing(crossing_file, t_ck)
        monitor.first_crossing = None if saved is None else asdict(saved)
    try:
        res = solve_flow(model, sc.initial(N), t_final, N=N, tol=sc.tol, t_eval=snaps,
                         checkpoint=ck, resume=ck if resuming else None, progress=progress,
                         checkpoint_interval=checkpoint_interval, callback=observe)
    finally:  # also on Ctrl-C, so that a resumed run finds the series up to its checkpoint
        series.save()
    system = res.system
    a = series.arrays()
    fc = monitor.first_crossing
    first_crossing = None if fc is None else Crossing.from_record(fc)
    x0, y0 = system.positions(system.y0)
    run = CHARun(
        name=name, scenario=sc, N=N, t_final=float(t_final), success=bool(res.success),
        message=res.message, L0=float(system.L0), final_length=float(res.length[-1]),
        sheets=paired_sheets(res.x, res.y, target), t=a["t"], energy=a["energy"],
        length=a["length"], crossing=a["crossing"], approach=a["approach"],
        t_steps=res.t_steps, energy_steps=res.energy_steps, snap_t=res.t,
        snap_x=res.states[:, :N], snap_y=res.states[:, N : 2 * N], snap_energy=res.energy,
        x0=x0, y0=y0, first_crossing=first_crossing, n_steps=int(res.n_steps),
        n_rejected=int(res.n_rejected), n_newton=int(res.n_newton),
        wall_seconds=time.perf_counter() - wall0, checkpoint=ck, result=res)
    if out is None:
        return run
    return replace(run, files=tuple(write_output(out, name, run.arrays(), run.summary())))


def _load_crossing(path, t_max):
    """The first crossing saved before the checkpoint at ``t_max`` (or None)."""
    if path is None or not os.path.isfile(path):
        return None
    a, _ = load_npz(path)
    if float(a["crossing_t"]) > t_max * (1 + 1e-12):
        return None
    return Crossing.from_arrays(a)


def run_folding(scenarios, out=None, **options):
    """:func:`run_cha` for each scenario (sorted by ``rho``): f:fold.

    Parameters
    ----------
    scenarios : iterable of CHAScenario
        Typically identical but for ``rho``.
    out : str, optional
        Output folder; each run writes its own ``cha_rho<rho>...`` files (and
        resumes from its own checkpoint).
    **options
        Passed to :func:`run_cha` (``t_final``, ``N``, ``resume``, ``progress`` ...).

    Returns
    -------
    FoldingRun
    """
    runs = [run_cha(sc, out, **options) for sc in sorted(scenarios, key=lambda s: s.rho)]
    return FoldingRun(tuple(runs))


def resolution_check(scenario=None, N=None, t_short=2e-3, *, progress=None):
    """Run ``scenario`` at ``N`` and ``2N`` to ``t_short``; compare positions at common nodes.

    Node ``j`` of the N run and node ``2j`` of the 2N run sit at the same
    parameter ``s = j/N`` (equal chords, same first node).

    Returns
    -------
    ResolutionCheck
        ``max_difference`` (max over nodes of the position difference), its
        ratio to ``l*`` (CHA), and per run (N, 2N) ``wall``, ``steps``,
        ``success``.
    """
    sc = CHAScenario() if scenario is None else scenario
    N = sc.N if N is None else int(N)
    wall, steps, success, pos = [], [], [], {}
    for n in (N, 2 * N):
        w0 = time.perf_counter()
        res = solve_flow(sc.model(), sc.initial(n), t_short, N=n, tol=sc.tol,
                         progress=progress)
        wall.append(time.perf_counter() - w0)
        steps.append(int(res.n_steps))
        success.append(bool(res.success))
        pos[n] = (res.x, res.y)
    d = np.hypot(pos[N][0] - pos[2 * N][0][::2], pos[N][1] - pos[2 * N][1][::2])
    scale = getattr(sc, "l_star", None)
    return ResolutionCheck(N, float(t_short), tuple(wall), tuple(steps), tuple(success),
                           float(d.max()), float(d.max() / scale) if scale else None)
