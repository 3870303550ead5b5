"""Running a sweep: executors, the point files on disk, the results table, :func:`run_sweep`.

:mod:`qsa.sweep` describes the storage and resumption; the grids are
:mod:`qsa.sweep.grid`.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import hashlib
import inspect
import io
import json
import multiprocessing as mp
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from qsa._version import __version__
from qsa.npz import write_atomically
from qsa.sweep.grid import ParameterGrid, _python, _scalar, point_key

__all__ = [
    "SweepResult",
    "SweepWarning",
    "SerialExecutor",
    "dask_executor",
    "run_sweep",
    "read_table",
    "load_point",
    "STATUS_COLUMNS",
]

#: Columns every table has after the parameters.
STATUS_COLUMNS = ("success", "message")


class SweepWarning(UserWarning):
    """A stored point could not be read back and is recomputed."""


class SerialExecutor(cf.Executor):
    """Runs each task at submission, in the calling process (``workers=1``, debugging)."""

    def submit(self, fn, /, *args, **kwargs):
        """Run ``fn(*args, **kwargs)`` now; a finished ``Future`` holds its result or error."""
        fut = cf.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # delivered through the future, like a pool
            fut.set_exception(exc)
        return fut


@contextlib.contextmanager
def dask_executor(address=None, n_workers=None, threads_per_worker=1):
    """A ``concurrent.futures`` executor on a Dask cluster (lazy import of distributed).

    Parameters
    ----------
    address : str, optional
        Scheduler address (``"tcp://host:8786"``) of a running cluster.
    n_workers : int, optional
        Without ``address``: start a :class:`distributed.LocalCluster` with this many
        worker processes (closed on exit).

    Yields
    ------
    concurrent.futures.Executor
        ``distributed.Client(...).get_executor()``.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - the extra is installed in CI
        raise ImportError("Dask sweeps need the optional extra: "
                          "pip install 'qsa-interfaces[dask]'") from exc
    if (address is None) == (n_workers is None):
        raise ValueError("dask_executor: give exactly one of address and n_workers")
    if address is not None:
        with Client(address) as client:
            yield client.get_executor()
        return
    if int(n_workers) < 1:
        raise ValueError(f"n_workers must be >= 1, got {n_workers}")
    with LocalCluster(n_workers=int(n_workers), threads_per_worker=threads_per_worker,
                      processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        yield client.get_executor()


# ------------------------------------------------------------- point files
def _atomic_write(path: Path, data: bytes):
    """Write ``data`` to ``path`` so that readers see the old file or the whole new one."""
    write_atomically(path, lambda fh: fh.write(data))


def _is_scalar(v) -> bool:
    return isinstance(v, (bool, int, float, str, np.generic)) and np.ndim(v) == 0


def _split_result(result, study_name):
    if not isinstance(result, dict):
        raise TypeError(f"study {study_name} returned {type(result).__name__}, expected a dict")
    scalars, arrays = {}, {}
    for k, v in result.items():
        if k in STATUS_COLUMNS:
            raise ValueError(f"study {study_name}: result name {k!r} is reserved")
        if _is_scalar(v):
            scalars[k] = _python(v)
        else:
            a = np.asarray(v)
            if a.dtype == object:
                raise TypeError(f"study {study_name}: result {k!r} is not a numeric array")
            arrays[k] = a
    return scalars, arrays


def _compute_point(study, params):
    """Worker side: evaluate one point; exceptions become a failed point."""
    t0 = time.perf_counter()
    try:
        result = study(**params)
        return {"success": True, "message": "", "result": result,
                "seconds": time.perf_counter() - t0}
    except Exception as exc:  # failure is data: stored and reported per point
        return {"success": False, "message": f"{type(exc).__name__}: {exc}", "result": {},
                "seconds": time.perf_counter() - t0}


def _store_point(points_dir: Path, key, study_name, params, outcome):
    scalars, arrays = _split_result(outcome["result"], study_name)
    clash = sorted(set(params) & (set(scalars) | set(arrays)))
    if clash:
        raise ValueError(f"study {study_name} returns {clash}, which are also its "
                         "parameters: rename the results")
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    blob = buf.getvalue()
    meta = {"study": study_name, "params": params, "success": outcome["success"],
            "message": outcome["message"], "results": scalars, "arrays": sorted(arrays),
            "seconds": outcome["seconds"], "npz_sha256": hashlib.sha256(blob).hexdigest(),
            "qsa_version": __version__}
    _atomic_write(points_dir / f"{key}.npz", blob)
    _atomic_write(points_dir / f"{key}.json", json.dumps(meta, indent=1).encode())
    return meta


def load_point(points_dir, key, study_name=None, params=None, arrays=False):
    """Read one stored point back; ``ValueError`` (naming the file) if it is damaged.

    Returns
    -------
    dict
        The JSON metadata; with ``arrays=True`` also ``"data"``: the npz arrays.
    """
    points_dir = Path(points_dir)
    jpath, npath = points_dir / f"{key}.json", points_dir / f"{key}.npz"
    try:
        meta = json.loads(jpath.read_text())
        if not isinstance(meta, dict) or not {"params", "success", "results"} <= set(meta):
            raise ValueError("missing fields")
        blob = npath.read_bytes()
        if hashlib.sha256(blob).hexdigest() != meta.get("npz_sha256"):
            raise ValueError("npz checksum mismatch (truncated or modified)")
        if study_name is not None and meta.get("study") != study_name:
            raise ValueError(f"stored for study {meta.get('study')!r}")
        if params is not None and meta["params"] != params:
            raise ValueError(f"stored for params {meta['params']}")
        if arrays:
            with np.load(io.BytesIO(blob), allow_pickle=False) as z:
                meta["data"] = {k: z[k] for k in z.files}
    except (OSError, ValueError, json.JSONDecodeError, KeyError) as exc:
        raise ValueError(f"point file {jpath} (or its .npz) is unreadable: {exc}") from None
    return meta


# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class SweepResult:
    """The outcome of :func:`run_sweep`.

    Attributes
    ----------
    rows : list of dict
        One per grid point, in grid order: parameters, ``success``, ``message`` and the
        study's scalar results (missing ones are NaN).
    columns : list of str
    table_path : Path
        ``results.csv`` in the output directory.
    out : Path
    n_points, n_computed, n_reused, n_failed, n_recomputed_corrupt : int
    seconds : float
        Wall time of this run.
    success : bool
        Every point computed without an exception.
    message : str
    """

    rows: list
    columns: list
    table_path: Path
    out: Path
    n_points: int
    n_computed: int
    n_reused: int
    n_failed: int
    n_recomputed_corrupt: int
    seconds: float
    success: bool
    message: str
    keys: list = field(default_factory=list, repr=False)
    study: str = ""

    def column(self, name) -> np.ndarray:
        """One column as an array (floats where possible)."""
        vals = [r.get(name, np.nan) for r in self.rows]
        try:
            return np.asarray(vals, dtype=float)
        except (TypeError, ValueError):
            return np.asarray(vals, dtype=object)

    def arrays(self, i) -> dict:
        """The stored arrays of row ``i`` (npz, read with ``allow_pickle=False``)."""
        return load_point(self.out / "points", self.keys[i], arrays=True)["data"]

    def summary(self) -> dict:
        return {"study": self.study, "out": str(self.out), "table": str(self.table_path),
                "n_points": self.n_points, "n_computed": self.n_computed,
                "n_reused": self.n_reused, "n_failed": self.n_failed,
                "n_recomputed_corrupt": self.n_recomputed_corrupt,
                "seconds": self.seconds, "success": self.success, "message": self.message}


def _write_table(path: Path, columns, rows):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_csv_cell(r.get(c, "")) for c in columns])
    _atomic_write(path, buf.getvalue().encode())


def _csv_cell(v):
    if isinstance(v, float):
        return repr(v)  # shortest round-trip representation
    return v


def read_table(path) -> list:
    """Read a sweep's ``results.csv`` back as a list of row dicts (numbers parsed)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return [{k: (_scalar(v) if k != "message" else v) for k, v in r.items()} for r in rows]


def _study_name(study) -> str:
    return f"{study.__module__}.{study.__qualname__}"


def _check_params(study, grid: ParameterGrid):
    sig = inspect.signature(study)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return
    unknown = [n for n in grid.names if n not in sig.parameters]
    if unknown:
        raise ValueError(f"params: {unknown} are not parameters of {_study_name(study)} "
                         f"(it takes {list(sig.parameters)})")


def _progress_bar(total, progress):
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="sweep", unit="pt")


_BLAS_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextlib.contextmanager
def _environ(values):
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _default_executor(stack, workers, blas_threads):
    """In-process for one worker, else a process pool of fresh (spawned) interpreters."""
    n = int(workers) if workers is not None else (os.cpu_count() or 1)
    if n == 1:
        return SerialExecutor()
    pool = cf.ProcessPoolExecutor(n, mp_context=mp.get_context("spawn"))
    stack.callback(pool.shutdown, wait=True, cancel_futures=True)
    if blas_threads is not None:
        # workers start (lazily, at submission) with this environment: their BLAS uses
        # blas_threads threads, as the pool already keeps every core busy
        stack.enter_context(_environ({v: str(int(blas_threads)) for v in _BLAS_VARS}))
    return pool


def run_sweep(study, params, out, executor=None, workers=None, progress=None,
              on_corrupt="recompute", blas_threads=1):
    """Evaluate ``study`` on every point of ``params``, storing each point in ``out``.

    Parameters
    ----------
    study : callable
        Module-level function ``study(**point) -> dict`` (picklable by reference).
    params : ParameterGrid, dict or list of str
        The grid: a :class:`ParameterGrid`, ``{"alpha": [...], ...}`` or specs such as
        ``["alpha=0.05:0.3:11", "n_pulses=2,3,4"]``.
    out : str or Path
        Output directory (created): ``points/`` and ``results.csv``, ``sweep.json``.
    executor : concurrent.futures.Executor, optional
        Where points run; not shut down here. Default: a ``ProcessPoolExecutor`` with
        ``workers`` processes (``workers=1``: in this process, :class:`SerialExecutor`).
    workers : int, optional
        Size of the default process pool (default ``os.cpu_count()``). Its workers are
        spawned (fresh interpreters), so a script that runs a sweep on it needs the
        usual ``if __name__ == "__main__":`` guard.
    blas_threads : int or None
        BLAS/OpenMP threads of each worker of the default pool (environment variables
        set when the spawned workers start); ``None`` leaves the environment alone.
    progress : bool, optional
        tqdm progress bar; default: only when stderr is a terminal.
    on_corrupt : {"recompute", "raise"}
        What to do with a stored point that cannot be read back.

    Returns
    -------
    SweepResult

    Raises
    ------
    ValueError
        Unknown parameter names, a bad ``on_corrupt``, a damaged point file with
        ``on_corrupt="raise"``, or ``out`` holding a sweep of another study.
    """
    t_start = time.perf_counter()
    if on_corrupt not in ("recompute", "raise"):
        raise ValueError(f"on_corrupt must be 'recompute' or 'raise', got {on_corrupt!r}")
    if workers is not None and (isinstance(workers, bool) or int(workers) < 1):
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    if not isinstance(params, ParameterGrid):
        params = (ParameterGrid.from_dict(params) if isinstance(params, dict)
                  else ParameterGrid.parse(params))
    _check_params(study, params)
    name = _study_name(study)
    out = Path(out)
    points_dir = out / "points"
    points_dir.mkdir(parents=True, exist_ok=True)
    manifest = out / "sweep.json"
    if manifest.exists():
        try:
            old = json.loads(manifest.read_text()).get("study")
        except (OSError, ValueError):
            old = None
        if old is not None and old != name:
            raise ValueError(f"out: {out} holds a sweep of {old}, not {name}")
    _atomic_write(manifest, json.dumps({"study": name, "params": params.to_json(),
                                        "qsa_version": __version__}, indent=1).encode())

    for stale in points_dir.glob(".*.tmp"):  # half-written files of a killed run
        with contextlib.suppress(OSError):
            stale.unlink()
    points = params.points()
    keys = [point_key(name, p) for p in points]
    metas, todo, n_corrupt, seen = {}, [], 0, set()
    for key, p in zip(keys, points, strict=True):
        if key in seen:  # the same point twice in the grid
            continue
        seen.add(key)
        if (points_dir / f"{key}.json").exists():
            try:
                metas[key] = load_point(points_dir, key, name, p)
                continue
            except ValueError as exc:
                if on_corrupt == "raise":
                    raise
                warnings.warn(f"{exc}; recomputing it", SweepWarning, stacklevel=2)
                n_corrupt += 1
        todo.append((key, p))
    n_reused = len(metas)

    with contextlib.ExitStack() as stack:
        if executor is None and todo:
            executor = _default_executor(stack, workers, blas_threads)
        bar = _progress_bar(len(todo), progress)
        if bar is not None:
            stack.callback(bar.close)
        futures = {executor.submit(_compute_point, study, p): (key, p) for key, p in todo}
        for fut in cf.as_completed(futures):
            key, p = futures[fut]
            metas[key] = _store_point(points_dir, key, name, p, fut.result())
            if bar is not None:
                bar.update()

    result_names = []
    for key in keys:
        for k in metas[key]["results"]:
            if k not in result_names:
                result_names.append(k)
    columns = params.names + list(STATUS_COLUMNS) + result_names
    rows = []
    for key, p in zip(keys, points, strict=True):
        m = metas[key]
        row = dict(p)
        row.update(success=bool(m["success"]), message=m["message"])
        row.update({k: m["results"].get(k, np.nan) for k in result_names})
        rows.append(row)
    table = out / "results.csv"
    _write_table(table, columns, rows)
    n_failed = sum(not r["success"] for r in rows)
    msg = (f"{len(rows)} points: {len(todo)} computed, {n_reused} reused"
           + (f" ({n_corrupt} damaged point files recomputed)" if n_corrupt else "")
           + (f", {n_failed} failed" if n_failed else ""))
    return SweepResult(rows, columns, table, out, len(rows), len(todo), n_reused, n_failed,
                       n_corrupt, time.perf_counter() - t_start, n_failed == 0, msg, keys,
                       name)
