"""Parameter sweeps: map a study over a grid of parameters with any executor.

A *study* is a picklable module-level function ``study(**params) -> dict`` (see
:mod:`qsa.studies`). Its result maps names to scalars (``float``, ``int``,
``bool``, ``str``; they become columns of the table) or arrays (stored per point).
:func:`run_sweep` evaluates it at every point of a :class:`ParameterGrid` with a
:class:`concurrent.futures.Executor` — a local :class:`~concurrent.futures.ProcessPoolExecutor`
by default, a Dask cluster through ``distributed.Client(...).get_executor()``
(:func:`dask_executor`, the optional extra ``qsa-interfaces[dask]``) or any other.

Storage and resumption
----------------------
Every finished point is written by the calling process as ``points/<key>.npz``
(its arrays; read back with ``allow_pickle=False``) and ``points/<key>.json``
(parameters, scalar results, ``success``/``message``, run time, the SHA-256 of the
npz). Both are written atomically (temporary file in the same directory, then
``os.replace``) and the JSON last, so a point counts as finished only once both
are complete: a sweep killed at any moment (even ``SIGKILL``) leaves finished
points readable and re-running it computes only the missing ones. The table
``results.csv`` (one row per grid point, in grid order) is rebuilt from the point
files at the end of each run; it holds no timings, so the same sweep gives the
same table on any executor.

A point file that cannot be read back (truncated, not JSON, wrong SHA-256, other
parameters than its key) is *recomputed* by default (with a :class:`SweepWarning`
naming the file); ``on_corrupt="raise"`` raises ``ValueError`` naming it instead.
A study that raises on a point is a *failed point* (``success=False`` and the
exception text in ``message``); it is stored like any other and not retried.

Workers never touch the output directory (the results travel back through the
executor), so a cluster needs no shared file system. One sweep writes to a directory
at a time: a new run removes the temporary files a killed one left behind.

Examples
--------
>>> grid = ParameterGrid.parse(["alpha=0.1:0.2:3", "n_pulses=2,3"])
>>> len(grid), grid.points()[1]
(6, {'alpha': 0.1, 'n_pulses': 3})
"""

from qsa.sweep.grid import ParameterGrid, parse_param, point_key
from qsa.sweep.run import (
    STATUS_COLUMNS,
    SerialExecutor,
    SweepResult,
    SweepWarning,
    dask_executor,
    load_point,
    read_table,
    run_sweep,
)

__all__ = [
    "ParameterGrid",
    "SweepResult",
    "SweepWarning",
    "SerialExecutor",
    "dask_executor",
    "parse_param",
    "point_key",
    "run_sweep",
    "read_table",
    "load_point",
    "STATUS_COLUMNS",
]
