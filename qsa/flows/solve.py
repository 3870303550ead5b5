"""``solve_flow``: run a DAE curve flow from closed initial data (appendix "Discussion of
Numerical Scheme").

The driver prepares the initial data (resampling to N nodes of equal chords,
the paper's ap:scaled, with the first sample kept as the first node), binds the
model (``model.setup``), and advances the :class:`~qsa.flows.stepper.Integrator`
to ``t_final`` in physical time, recording snapshots, energy and length
histories, counters, optional checkpoints and a progress bar.

Checkpoints are single ``.npz`` files with JSON metadata written atomically
(:mod:`qsa.io`). They hold the full integrator state, including the points at
which the pooled Newton matrices were factorized, so ``resume=`` rebuilds the
same matrices and a resumed run repeats the uninterrupted one (to round-off;
in practice bit for bit).

Ctrl-C (SIGINT) during a run in the main thread stops it at the end of the
current step: the checkpoint is written (to a temporary file when none was
given) and :class:`FlowInterrupted`, a ``KeyboardInterrupt`` carrying the
checkpoint's path, is raised; resuming from it repeats the uninterrupted run
exactly. A second Ctrl-C aborts at once.
"""

from __future__ import annotations

import inspect
import json
import os
import signal
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from qsa._checks import integer, real_number
from qsa._version import __version__
from qsa.constraints import check_constraints
from qsa.curve import Curve
from qsa.flows.models.constrained import polygon_area
from qsa.flows.stepper import LINEAR_SOLVERS, METHODS, Integrator, NewtonSolver
from qsa.npz import load_npz, save_npz
from qsa.polygon import self_intersections
from qsa.resample import closed_samples, resample_closed

if TYPE_CHECKING:
    from qsa.flows.base import DAESystem

__all__ = ["solve_flow", "FlowResult", "FlowInterrupted", "prepare_initial"]

_KIND = "qsa.flow-checkpoint"

#: Meaning of :attr:`FlowResult.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`FlowResult.message` starts with the entry.
MESSAGES = {
    0: "The flow reached t_final.",
    1: "Stopped by the callback.",
    -1: "Newton failed to converge with the step halved below min_step.",
    -2: "The step limit max_steps was reached before t_final.",
}


class FlowInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped :func:`solve_flow` after a step; the run is saved in ``checkpoint``.

    Attributes
    ----------
    checkpoint : str
        The file to pass as ``resume=`` to continue the run.
    t : float
        The time reached (the checkpoint's time).
    """

    def __init__(self, checkpoint, t):
        super().__init__(f"interrupted at t = {t:.6g}; checkpoint {checkpoint}")
        self.checkpoint = checkpoint
        self.t = t


@dataclass(frozen=True)
class FlowResult:
    """Result of :func:`solve_flow`.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Snapshot times (``t_eval``, or every accepted step when ``t_eval`` is
        ``None``); the last entry is the final time reached.
    states : ndarray, shape (n, size)
        Full DAE states at ``t`` (use ``system.unpack`` or :meth:`positions`).
    energy, length : ndarray, shape (n,)
        Discrete energy and curve length at ``t``.
    t_steps, energy_steps, length_steps : ndarray, shape (n_steps + 1,)
        Time, energy and length after every accepted step (and at t = 0).
    success : bool
        ``status >= 0``.
    status : int
        A key of :data:`MESSAGES`: 0 reached ``t_final``; 1 stopped by the callback;
        -1 Newton failure below ``min_step``; -2 ``max_steps`` reached.
    message : str
        Starts with ``MESSAGES[status]``.
    n_steps, n_rejected : int
        Accepted and rejected steps (for ``method="be"`` a step is one
        step-doubling pass: two backward Euler steps of ``k`` advancing time by
        ``2k``).
    n_newton, n_lu : int
        Newton iterations and matrix factorizations (``n_factorizations`` is a
        read-only alias of ``n_lu``).
    n_newton_failures : int
        Steps retried with a halved step after a Newton failure.
    checkpoint : str or None
        Path of the checkpoint file (also the last good state on failure).
    x, y : ndarray, shape (N,)
        Final node positions.
    method : str
    tol : float
    system : DAESystem
        The bound system (``unpack``, ``positions``, ``energy`` …).
    """

    t: np.ndarray
    states: np.ndarray
    energy: np.ndarray
    length: np.ndarray
    t_steps: np.ndarray
    energy_steps: np.ndarray
    length_steps: np.ndarray
    success: bool
    status: int
    message: str
    n_steps: int
    n_rejected: int
    n_newton: int
    n_lu: int
    n_newton_failures: int
    checkpoint: str | None
    x: np.ndarray
    y: np.ndarray
    method: str
    tol: float
    system: DAESystem = field(repr=False, compare=False)

    @property
    def n_factorizations(self) -> int:
        """Read-only alias of :attr:`n_lu` (the former name)."""
        return self.n_lu

    @property
    def N(self) -> int:
        return int(self.system.N)

    def positions(self, i=-1):
        """Node positions ``(x, y)`` of snapshot ``i``."""
        return self.system.positions(self.states[i])

    def areas(self) -> np.ndarray:
        """Polygon areas of the snapshots (conserved by a ``FixedArea`` flow), shape (n,)."""
        return np.array([polygon_area(*self.system.positions(y)) for y in self.states])

    def curvature(self, i=-1):
        """Curvature unknowns of snapshot ``i``, shape (N,)."""
        return self.system.unpack(self.states[i])["kappa"].copy()


# --------------------------------------------------------------- input checks
def prepare_initial(initial, N=None):
    """Closed samples or a ``Curve`` -> N nodes with equal chords (the first sample kept).

    Parameters
    ----------
    initial : Curve or (x, y)
        A :class:`qsa.Curve`, or a pair of arrays sampling a closed
        counter-clockwise curve (a repeated end point is dropped).
    N : int, optional
        Number of nodes (default: the number of samples).

    Returns
    -------
    x, y : ndarray, shape (N,)

    Raises
    ------
    ValueError
        For NaN, open or self-intersecting data, fewer than 4 points, or a bad N.
    """
    if isinstance(initial, Curve):
        x, y = initial.positions()
    else:
        try:
            x, y = initial
        except (TypeError, ValueError):
            raise ValueError("initial must be a Curve or a pair (x, y) of closed samples") \
                from None
    x, y = closed_samples(x, y, name="initial")
    crossings = self_intersections(x, y)
    if crossings.shape[0]:
        raise ValueError(f"initial: the curve intersects itself (segments "
                         f"{crossings[0, 0]} and {crossings[0, 1]} cross)")
    if N is None:
        N = x.size
    N = integer(N, "N", minimum=4, too_small="{name} must be an integer >= {minimum}, got {value}")
    X, Y, _ = resample_closed(x, y, N, method="chord")
    return X, Y


# --------------------------------------------------------------- the driver
def solve_flow(model, initial, t_final, N=None, tol=1e-4, method="be", t_eval=None, *,
               first_step=2e-5, min_step=None, max_step=None, max_steps=1_000_000,
               newton_tol=None, linear_solver="auto", reuse_factorizations=True,
               checkpoint=None, checkpoint_interval=10.0, resume=None, progress=None,
               callback=None, constraints=None):
    """Evolve a closed curve by a DAE flow model to ``t_final`` (physical time).

    Parameters
    ----------
    model : FlowModel
        ``CHA(...)`` or ``FacetingFlow(...)``.
    initial : Curve or (x, y)
        Initial curve; samples are resampled to ``N`` nodes with equal chords
        (the first sample stays the first node). Ignored when resuming.
    t_final : float
        Final physical time.
    N : int, optional
        Number of nodes (default: number of samples / ``Curve.N``).
    tol : float
        Local error tolerance on the node positions (absolute, max norm); for
        ``"be"`` the paper's step-doubling estimate, for ``"bdf2"`` the
        divided-difference estimate.
    method : {"be", "bdf2"}
        Backward Euler with step doubling (the paper's scheme) or variable-step
        BDF2.
    t_eval : array_like, optional
        Snapshot times in ``[0, t_final]``; steps are shortened to land on them.
        Default: a snapshot after every accepted step.
    first_step : float
        First step in physical time (default ``2e-5``: the paper's two steps of
        ``1e-5``).
    min_step, max_step : float, optional
        Step bounds (default ``1e-12 t_final`` and ``t_final``).
    max_steps : int
        Largest number of accepted steps (then ``status=-2``).
    newton_tol : float, optional
        Absolute Newton tolerance on positions and L (default ``1e-2 tol``; the
        reproductions of the paper use ``1e-3 tol``, closer to its tight Newton).
    linear_solver : {"auto", "sparse", "woodbury", "dense"}
        See :func:`qsa.flows.stepper.factorize`.
    reuse_factorizations : bool
        Simplified Newton with pooled factorizations (default) or full Newton.
    checkpoint : str or path, optional
        File written atomically every ``checkpoint_interval`` seconds of wall
        time, at the end, and on failure.
    checkpoint_interval : float
        Seconds between checkpoints (0: after every accepted step).
    resume : str or path, optional
        Continue the run saved in this checkpoint (``initial`` and ``N`` are
        taken from it; ``model``, ``method`` and ``tol`` must match, ``N`` if
        given too, and ``t_final`` must not be before the checkpoint's time).
        Unless ``checkpoint`` is given, the same file keeps being updated.
    progress : bool, optional
        tqdm progress bar; default: only when stderr is a terminal.
    callback : callable, optional
        ``callback(t, y, system)`` after every accepted step; returning
        ``True`` stops the run (``status=1``).
    constraints : sequence of Constraint, optional
        ``[FixedLength()]``, ``[FixedArea()]`` or both (:mod:`qsa.constraints`): a
        length- and/or area-preserving flow, the multipliers enforcing the constraints
        as extra DAE unknowns (:mod:`qsa.flows.models.constrained`). ``None`` targets
        are the initial curve's values (after resampling); a given target must equal
        them. On resume they are read from the checkpoint.

    Returns
    -------
    FlowResult

    Raises
    ------
    ValueError
        For bad input: NaN, open or self-intersecting initial data, ``tol <= 0``,
        a grid too coarse for the model (e.g. ``L/N > l_star``), a checkpoint
        that is corrupt or belongs to another run (another model, method, tol or
        N), a ``t_final`` before the checkpoint's time.
    FlowInterrupted
        Ctrl-C: the run stopped after a step and was saved (see the module notes).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.flows import CHA, solve_flow
    >>> th = 2 * np.pi * np.arange(200) / 200
    >>> r = 1 + 0.2 * np.cos(3 * th)
    >>> res = solve_flow(CHA(eps=0.1, beta=1.0, rho=1.2), (r * np.cos(th), r * np.sin(th)),
    ...                  0.01, N=48, tol=1e-3)
    >>> res.success, bool(res.energy[-1] < res.energy[0])
    (True, True)
    """
    t_final = real_number(t_final, "t_final", positive=True)
    tol = real_number(tol, "tol", positive=True)
    if method not in METHODS:
        raise ValueError(f"method must be one of {tuple(METHODS)}, got {method!r}")
    if linear_solver not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {LINEAR_SOLVERS}, got {linear_solver!r}")
    first_step = real_number(first_step, "first_step", positive=True)
    min_step = (1e-12 * t_final if min_step is None
                else real_number(min_step, "min_step", positive=True))
    max_step = t_final if max_step is None else real_number(max_step, "max_step", positive=True)
    newton_tol = (1e-2 * tol if newton_tol is None
                  else real_number(newton_tol, "newton_tol", positive=True))
    max_steps = integer(max_steps, "max_steps", minimum=1)
    checkpoint_interval = float(checkpoint_interval)
    if callback is not None and not callable(callback):
        raise ValueError("callback must be callable")
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float).ravel()
        if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
            raise ValueError("t_eval must be a non-empty array of finite times")
        if np.any(np.diff(t_eval) <= 0) or t_eval[0] < 0 or t_eval[-1] > t_final * (1 + 1e-12):
            raise ValueError("t_eval must be strictly increasing within [0, t_final]")

    options = {"method": method, "tol": tol}
    constraints = check_constraints(constraints)
    if constraints and "constraints" not in inspect.signature(model.setup).parameters:
        raise ValueError(f"constraints: the model {type(model).__name__} does not support "
                         "length / area constraints")
    if resume is not None:
        loaded = _load_checkpoint(resume, model, options)
        x0, y0, bound = loaded["x_setup"], loaded["y_setup"], loaded["bound"]
        _check_resume(resume, loaded, N, t_final)
        system = model.setup(x0, y0, **bound)
        saved = getattr(system, "constraints", ())
        if constraints and not _same_constraints(constraints, saved):
            raise ValueError("constraints: the checkpoint was written with "
                             f"{[k.params() for k in saved]}; resume without constraints= "
                             "(they are read from the checkpoint)")
    else:
        x0, y0 = prepare_initial(initial, N)
        system = model.setup(x0, y0, constraints=constraints) if constraints else \
            model.setup(x0, y0)
    index = np.union1d(system.error_index, [system.size - 1])
    newton = NewtonSolver(system, newton_tol, index, strategy=linear_solver,
                          reuse=reuse_factorizations)
    integ = Integrator(system, method, tol, first_step, min_step, max_step, newton)

    rec = _Recorder(system, t_eval)
    if resume is not None:
        integ.set_state(loaded["scalars"], loaded["arrays"])
        rec.restore(loaded["arrays"])
        if checkpoint is None:
            checkpoint = resume
    else:
        rec.record_step(0.0, integ.y)
    checkpoint = None if checkpoint is None else os.fspath(checkpoint)

    def write(status):
        scalars, arrays = integ.get_state()
        arrays.update(rec.arrays())
        arrays["x_setup"], arrays["y_setup"] = x0, y0
        meta = {"kind": _KIND, "version": __version__, "model": system.metadata(),
                "bound": system.bound_constants() if hasattr(system, "bound_constants") else {},
                "options": options, "integrator": scalars, "status": status,
                "t_final": t_final}
        return save_npz(path_for_write, arrays, meta)

    path_for_write = checkpoint
    status, last_write, bar = 0, time.monotonic(), None
    stop_request = _StopRequest()
    try:
        bar = _progress_bar(progress, integ.t, t_final)
        while integ.t < t_final:
            if stop_request.pending:
                if checkpoint is None:
                    path_for_write = checkpoint = _temporary_checkpoint("interrupted")
                write("interrupted")
                raise FlowInterrupted(checkpoint, integ.t)
            if integ.n_steps >= max_steps:
                status = -2
                break
            t_stop = rec.next_stop(integ.t, t_final)
            t_before = integ.t
            outcome = integ.step(t_stop)
            if outcome != "accepted":
                status = -1
                break
            rec.record_step(integ.t, integ.y)
            if bar is not None:
                bar.update(integ.t - t_before)
            stop = callback is not None and callback(integ.t, integ.y.copy(), system) is True
            if checkpoint is not None and (time.monotonic() - last_write >= checkpoint_interval):
                write("running")
                last_write = time.monotonic()
            if stop:
                status = 1
                break
    finally:
        stop_request.restore()
        if bar is not None:
            bar.close()
    if status == -1 and checkpoint is None:
        path_for_write = checkpoint = _temporary_checkpoint("failed")
    if checkpoint is not None:
        write({0: "finished", 1: "stopped", -1: "failed", -2: "max_steps"}[status])
    rec.finish(integ.t, integ.y)
    message = MESSAGES[status]
    if status == -1:
        message += f" Last good state (t = {integ.t:.6g}) saved in {checkpoint}."
    X, Y = system.positions(integ.y)
    return FlowResult(
        t=rec.t_array(), states=rec.state_array(), energy=np.array(rec.snap_E),
        length=np.array(rec.snap_L), t_steps=np.array(rec.step_t),
        energy_steps=np.array(rec.step_E), length_steps=np.array(rec.step_L),
        success=status >= 0, status=status, message=message, n_steps=integ.n_steps,
        n_rejected=integ.n_rejected, n_newton=newton.n_iterations,
        n_lu=newton.n_factorizations, n_newton_failures=integ.n_newton_failures,
        checkpoint=checkpoint, x=X, y=Y, method=method, tol=tol, system=system)


def _same_constraints(given, saved) -> bool:
    """The same kinds in the same order, and equal targets where ``given`` has one."""
    return len(given) == len(saved) and all(
        type(a) is type(b) and (a.target is None or a.target == b.target)
        for a, b in zip(given, saved, strict=True))


class _Recorder:
    """Snapshots (at t_eval or every step) and per-step energy/length histories."""

    def __init__(self, system, t_eval):
        self.system = system
        self.t_eval = t_eval
        self.snap_t, self.snap_y, self.snap_E, self.snap_L = [], [], [], []
        self.step_t, self.step_E, self.step_L = [], [], []

    def next_stop(self, t, t_final):
        if self.t_eval is None:
            return t_final
        later = self.t_eval[self.t_eval > t * (1 + 1e-14) + 1e-300]
        return float(later[0]) if later.size else t_final

    def record_step(self, t, y):
        E, L = self.system.energy(y), self.system.length(y)
        self.step_t.append(t)
        self.step_E.append(E)
        self.step_L.append(L)
        if self.t_eval is None or np.any(np.abs(self.t_eval - t) <= 1e-12 * max(1.0, abs(t))):
            self.snap_t.append(t)
            self.snap_y.append(np.array(y))
            self.snap_E.append(E)
            self.snap_L.append(L)

    def finish(self, t, y):
        """Make the final state the last snapshot (a run that stopped early)."""
        if not self.snap_t or self.snap_t[-1] != t:
            self.snap_t.append(t)
            self.snap_y.append(np.array(y))
            self.snap_E.append(self.system.energy(y))
            self.snap_L.append(self.system.length(y))

    def t_array(self):
        return np.array(self.snap_t)

    def state_array(self):
        return np.array(self.snap_y).reshape(len(self.snap_y), self.system.size)

    def arrays(self):
        return {"snap_t": self.t_array(), "snap_y": self.state_array(),
                "snap_E": np.array(self.snap_E), "snap_L": np.array(self.snap_L),
                "step_t": np.array(self.step_t), "step_E": np.array(self.step_E),
                "step_L": np.array(self.step_L)}

    def restore(self, a):
        self.snap_t = [float(v) for v in a["snap_t"]]
        self.snap_y = [np.array(v) for v in a["snap_y"]]
        self.snap_E = [float(v) for v in a["snap_E"]]
        self.snap_L = [float(v) for v in a["snap_L"]]
        self.step_t = [float(v) for v in a["step_t"]]
        self.step_E = [float(v) for v in a["step_E"]]
        self.step_L = [float(v) for v in a["step_L"]]


class _StopRequest:
    """A SIGINT handler, while a run lasts, that asks the loop to stop after the step.

    Installed only in the main thread (where Python delivers signals); a second
    SIGINT restores the previous handler's behaviour (``KeyboardInterrupt`` now).
    """

    def __init__(self):
        self.pending = False
        self.previous = None
        if threading.current_thread() is threading.main_thread():
            try:
                self.previous = signal.signal(signal.SIGINT, self._handle)
            except (ValueError, OSError):  # not the main interpreter, or no signals
                self.previous = None

    def _handle(self, signum, frame):
        if self.pending:
            self.restore()
            raise KeyboardInterrupt
        self.pending = True
        print("\nstopping after this step to save the checkpoint (Ctrl-C again to abort "
              "now)", file=sys.stderr, flush=True)

    def restore(self):
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
            self.previous = None


def _temporary_checkpoint(why):
    fd, path = tempfile.mkstemp(prefix=f"qsa-flow-{why}-", suffix=".npz")
    os.close(fd)
    return path


def _check_resume(path, loaded, N, t_final):
    """A resumed run keeps its grid and continues forward in time."""
    n_saved = int(loaded["arrays"]["x_setup"].size)
    if N is not None and int(N) != n_saved:
        raise ValueError(f"N={N}: the checkpoint {path} holds a run at N={n_saved}; a resumed "
                         "run keeps its grid (leave N out, or start a new run)")
    t_saved = float(loaded["scalars"]["t"])
    if t_final < t_saved * (1 - 1e-12):
        raise ValueError(f"t_final={t_final:g} is before the checkpoint's time t={t_saved:g} "
                         f"({path}); a resumed run continues forward: give t_final >= "
                         f"{t_saved:g}")


def _load_checkpoint(path, model, options):
    arrays, meta = load_npz(path)
    if meta.get("kind") != _KIND:
        raise ValueError(f"resume: {path} is not a flow checkpoint")
    saved_model = (meta.get("model") or {}).get("model")
    if saved_model is not None and saved_model != getattr(model, "name", saved_model):
        raise ValueError(f"resume: {path} is a checkpoint of a {saved_model} flow, not of "
                         f"{model.name}")
    need = ("x_setup", "y_setup", "y", "history_t", "history_y", "pool_c", "pool_y",
            "pool_ydot", "newton_theta", "be_slope", "snap_t", "snap_y", "snap_E", "snap_L",
            "step_t", "step_E", "step_L")
    missing = [n for n in need if n not in arrays]
    if missing:
        raise ValueError(f"resume: {path} lacks {missing} (corrupt checkpoint)")
    for key, value in options.items():
        if meta["options"].get(key) != value:
            raise ValueError(f"resume: the checkpoint was written with {key}="
                             f"{meta['options'].get(key)!r}, not {value!r}")
    x0, y0 = arrays["x_setup"], arrays["y_setup"]
    probe = model.setup(x0, y0, **meta.get("bound", {}))
    if _comparable(probe.metadata()) != _comparable(meta["model"]):
        raise ValueError(f"resume: {path} was written for model {meta['model']}, "
                         f"not {probe.metadata()}")
    return {"x_setup": x0, "y_setup": y0, "bound": meta.get("bound", {}), "arrays": arrays,
            "scalars": meta["integrator"]}


def _comparable(d):
    return json.loads(json.dumps(d, default=str))


def _progress_bar(progress, t0, t_final):
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=t_final, initial=t0, unit="t", unit_scale=False, dynamic_ncols=True,
                bar_format="{l_bar}{bar}| t={n:.4g}/{total:.4g} [{elapsed}<{remaining}]")
