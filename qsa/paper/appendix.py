"""The appendix's studies of the numerical scheme: Table ap:t1 and the time-step counts.

Both run the CHA example of :class:`~qsa.paper.scenarios.ConvergenceScenario`
(backward Euler with step doubling, to physical time 0.2: the paper's code
advances its clock by k per accepted pass of two steps of k, so the table's
"t = 0.1" is physical time 0.2).

* :func:`run_convergence` -- the max-norm difference of the final node
  positions of N and 2N at common nodes (node j of N is node 2j of 2N),
  componentwise as the paper's code measures position errors, for the paper
  code's centred-difference adhesion normal and/or the unit normal.
* :func:`run_timesteps` -- accepted step-doubling passes against the local
  error tolerance (the paper: x sqrt(10) per decade, as a local error O(k^2)
  controlled per pass implies), for backward Euler and BDF2.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsa.flows.solve import solve_flow
from qsa.paper.results import _Summarised
from qsa.paper.scenarios import CONVERGENCE

__all__ = ["ConvergenceStudy", "ConvergenceRun", "run_convergence", "StepCount",
           "TimestepRun", "run_timesteps", "count_steps", "growth_per_decade"]

#: adhesion-force normals of the convergence study (the CHA model's ``force_normal``)
NORMALS = {"centred": "paper's centred normal", "unit": "unit normal (qsa default)"}


def _keys(d):
    return {str(k): v for k, v in d.items()}


@dataclass(frozen=True, eq=False)
class ConvergenceStudy:
    """Final node positions per N and the differences between N and 2N (one force normal).

    Attributes
    ----------
    force_normal : str
    positions : dict of int -> ndarray, shape (2, N)
    steps : dict of int -> int
    seconds : dict of int -> float
        Wall time per run.
    differences : dict of int -> float
        ``max |X(2N) - X(N)|`` componentwise, for each N whose 2N was run.
    euclidean : dict of int -> float
        ``max_j |X_j(2N) - X_j(N)|``.
    """

    force_normal: str
    positions: dict
    steps: dict
    seconds: dict
    differences: dict
    euclidean: dict

    def ratios(self):
        """``{N: difference(N/2) / difference(N)}`` (4 for second order)."""
        Ns = sorted(self.differences)
        return {N: self.differences[Np] / self.differences[N]
                for Np, N in zip(Ns, Ns[1:], strict=False)}


@dataclass(frozen=True, eq=False)
class ConvergenceRun(_Summarised):
    """Table ap:t1 for one or both adhesion normals (:func:`run_convergence`)."""

    scenario: object
    tol: float
    t_final: float
    method: str
    studies: dict

    @property
    def rows(self):
        """The N with a difference in some study, sorted."""
        return sorted({N for s in self.studies.values() for N in s.differences})

    def summary(self):
        """The JSON summary (``qsa reproduce convergence --json``)."""
        paper = self.scenario.paper_differences
        out = {"t_final": self.t_final, "tol": self.tol, "method": self.method,
               "paper": _keys(paper), "results": {}}
        for n, s in self.studies.items():
            out["results"][n] = {
                "differences": _keys(s.differences),
                "euclidean": _keys(s.euclidean),
                "ratios": _keys(s.ratios()),
                "relative_to_paper": {str(k): s.differences[k] / paper[k]
                                      for k in s.differences if k in paper},
                "steps": _keys(s.steps),
                "seconds": _keys(s.seconds)}
        return out

    def arrays(self):
        """Final positions ``<normal>_N<N>``, shape (2, N) (``positions.npz``)."""
        return {f"{n}_N{N}": p for n, s in self.studies.items() for N, p in s.positions.items()}


def _study(scenario, Ns, tol, t_final, force_normal, method, verbose):
    model = scenario.model(force_normal)
    initial = scenario.samples()
    positions, steps, seconds, differences, euclidean = {}, {}, {}, {}, {}
    for N in sorted(Ns):
        t0 = time.perf_counter()
        res = solve_flow(model, initial, t_final, N=N, tol=tol, method=method,
                         t_eval=[t_final], progress=False, newton_tol=1e-3 * tol)
        if not res.success:
            raise RuntimeError(f"N={N}: {res.message}")
        positions[N] = np.array(res.positions(-1))
        steps[N] = res.n_steps
        seconds[N] = time.perf_counter() - t0
        if verbose:
            print(f"  [{force_normal}] N={N}: {res.n_steps} steps, {seconds[N]:.1f} s",
                  flush=True)
    for N in sorted(Ns):
        if 2 * N in positions:
            d = positions[N] - positions[2 * N][:, ::2]
            differences[N] = float(np.max(np.abs(d)))
            euclidean[N] = float(np.max(np.hypot(d[0], d[1])))
    return ConvergenceStudy(force_normal, positions, steps, seconds, differences, euclidean)


def run_convergence(scenario=CONVERGENCE, Ns=None, *, tol=None, t_final=None,
                    normals=("centred", "unit"), method="be", verbose=False):
    """Table ap:t1: final positions for each N and the differences between N and 2N.

    Parameters
    ----------
    scenario : ConvergenceScenario
    Ns : sequence of int, optional
        Resolutions (default ``scenario.Ns``).
    tol, t_final : float, optional
        Default the scenario's (1e-4, physical time 0.2).
    normals : sequence of {"centred", "unit"}
        Adhesion-force normals to run: the paper code's centred difference and/or
        the unit normal.
    method : {"be", "bdf2"}
    verbose : bool
        Print one line per finished run.

    Returns
    -------
    ConvergenceRun
        ``studies[normal]`` a :class:`ConvergenceStudy`. A failed solve raises
        ``RuntimeError`` (a table with a missing entry is no table).
    """
    Ns = scenario.Ns if Ns is None else Ns
    tol = scenario.tol if tol is None else float(tol)
    t_final = scenario.t_final if t_final is None else float(t_final)
    for n in normals:
        if n not in NORMALS:
            raise ValueError(f"normals must be among {sorted(NORMALS)}, got {n!r}")
    studies = {n: _study(scenario, Ns, tol, t_final, n, method, verbose) for n in normals}
    return ConvergenceRun(scenario, tol, t_final, method, studies)


# ---------------------------------------------------------------- time steps
@dataclass(frozen=True)
class StepCount:
    """Accepted steps, rejections, Newton iterations, factorizations and CPU seconds of a run.

    ``steps``, ``rejected`` and ``newton`` are read-only aliases of the counters (the
    former names).
    """

    n_steps: int
    n_rejected: int
    n_newton: int
    cpu_seconds: float
    n_lu: int = 0

    @property
    def steps(self) -> int:
        return self.n_steps

    @property
    def rejected(self) -> int:
        return self.n_rejected

    @property
    def newton(self) -> int:
        return self.n_newton

    def summary(self):
        return {"n_steps": self.n_steps, "n_rejected": self.n_rejected,
                "n_newton": self.n_newton, "n_lu": self.n_lu, "cpu_seconds": self.cpu_seconds}


def count_steps(tols, N=100, t_final=0.2, method="be", force_normal="centred",
                scenario=CONVERGENCE):
    """``{tol: StepCount}`` for the appendix example at ``N`` nodes."""
    model = scenario.model(force_normal)
    initial = scenario.samples()
    out = {}
    for tol in tols:
        t0 = time.process_time()
        res = solve_flow(model, initial, t_final, N=N, tol=tol, method=method,
                         t_eval=[t_final], progress=False, newton_tol=1e-3 * tol)
        if not res.success:
            raise RuntimeError(f"tol={tol:g}: {res.message}")
        out[tol] = StepCount(res.n_steps, res.n_rejected, res.n_newton,
                             time.process_time() - t0, res.n_lu)
    return out


def growth_per_decade(tols, steps):
    """Least-squares factor of steps per tenfold decrease of tol.

    Examples
    --------
    >>> round(growth_per_decade([1e-3, 1e-4, 1e-5], [10, 100, 1000]), 6)
    10.0
    """
    slope = np.polyfit(np.log10(tols), np.log10(steps), 1)[0]
    return float(10 ** (-slope))


@dataclass(frozen=True, eq=False)
class TimestepRun(_Summarised):
    """Steps against the tolerance for backward Euler and BDF2 (:func:`run_timesteps`).

    ``be`` and ``bdf2`` map each tolerance (descending) to a :class:`StepCount`;
    ``bdf2`` is empty when not run.
    """

    scenario: object
    N: int
    t_final: float
    force_normal: str
    tols: tuple
    be: dict
    bdf2: dict

    def growth_per_decade(self):
        """``{"be", "paper", "sqrt10"[, "bdf2"]}`` (None for fewer than two tolerances)."""
        if len(self.tols) < 2:
            return None
        paper = self.scenario.paper_steps
        ptols = sorted(paper, reverse=True)
        out = {"be": growth_per_decade(self.tols, [self.be[t].n_steps for t in self.tols]),
               "paper": growth_per_decade(ptols, [paper[t] for t in ptols]),
               "sqrt10": float(np.sqrt(10))}
        if self.bdf2:
            out["bdf2"] = growth_per_decade(self.tols,
                                            [self.bdf2[t].n_steps for t in self.tols])
        return out

    def summary(self):
        """The JSON summary (``qsa reproduce timesteps --json``)."""
        out = {"N": self.N, "t_final": self.t_final, "force_normal": self.force_normal,
               "paper": {f"{k:g}": v for k, v in self.scenario.paper_steps.items()},
               "be": {f"{k:g}": v.summary() for k, v in self.be.items()},
               "bdf2": {f"{k:g}": v.summary() for k, v in self.bdf2.items()}}
        g = self.growth_per_decade()
        if g is not None:
            out["growth_per_decade"] = g
        return out


def run_timesteps(scenario=CONVERGENCE, tols=None, *, N=None, t_final=None,
                  force_normal="centred", bdf2=True):
    """The appendix's time-step counts (paper: 65, 180, 571, 1811 at N = 100).

    Parameters
    ----------
    scenario : ConvergenceScenario
    tols : sequence of float, optional
        Default the paper's 1e-3 ... 1e-6 (run in descending order).
    N, t_final : optional
        Default ``scenario.N_steps`` (100) and ``scenario.t_final`` (0.2).
    force_normal : {"centred", "unit"}
    bdf2 : bool
        Also count BDF2's steps.

    Returns
    -------
    TimestepRun
    """
    tols = tuple(sorted(scenario.paper_steps if tols is None else tols, reverse=True))
    N = scenario.N_steps if N is None else int(N)
    t_final = scenario.t_final if t_final is None else float(t_final)
    be = count_steps(tols, N, t_final, "be", force_normal, scenario)
    bd = count_steps(tols, N, t_final, "bdf2", force_normal, scenario) if bdf2 else {}
    return TimestepRun(scenario, N, t_final, force_normal, tols, be, bd)
