"""Cost of ``qsa.sweep``: the same sweep on each executor, and the cost of resuming.

The headline study (``spectrum_study`` when ``qsa.spectra`` provides it, otherwise
``npulse_study``) on two grids of ``alpha`` x ``n_pulses = 2 .. 5``: a light one on
Fourier(121) (the 16 points of tests/test_sweep.py) and a heavy one at the resolving
grid size. Each runs in-process (``workers=1``), on a local process pool (2 spawned
workers: cold, start-up included, and warm) and on a warm Dask ``LocalCluster`` (2
worker processes; cluster start-up timed separately); then a second run over the finished directory
(every point reused) measures the overhead of checking the stored points.

Prints a table per grid: executor, points, wall seconds, ms per point, speed-up over
in-process. Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_sweep.py``.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import tempfile
import time
from pathlib import Path

from qsa.studies import STUDIES
from qsa.sweep import dask_executor, run_sweep

GRIDS = {
    "light (test grid)": ["alpha=0.16:0.19:4", "n_pulses=2,3,4,5", "N=121"],
    "heavy (resolving N)": ["alpha=0.1:0.16:4", "n_pulses=2,3,4,5"],
}


def study():
    try:
        from qsa import spectra

        if hasattr(spectra, "spectrum"):
            return STUDIES["spectrum"]
    except ImportError:
        pass
    return STUDIES["npulse"]


def warm_up():
    """Import what a point needs (run once in each worker before timing)."""
    import qsa.spectra  # noqa: F401
    import qsa.studies  # noqa: F401

    return os.getpid()


def warm(executor, n=8):
    list(executor.map(_sleep_then_warm, range(n)))


def _sleep_then_warm(_):
    time.sleep(0.05)  # spread the calls over the workers
    return warm_up()


def bench(st, specs):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        warm_up()
        r = run_sweep(st, specs, tmp / "serial", workers=1, progress=False)
        rows.append(("in-process", r.n_computed, r.seconds))
        r = run_sweep(st, specs, tmp / "pool-cold", workers=2, progress=False)
        rows.append(("process pool (2), cold", r.n_computed, r.seconds))
        with cf.ProcessPoolExecutor(2, mp_context=mp.get_context("spawn")) as pool:
            warm(pool)
            r = run_sweep(st, specs, tmp / "pool", executor=pool, progress=False)
            rows.append(("process pool (2), warm", r.n_computed, r.seconds))
        t0 = time.perf_counter()
        with dask_executor(n_workers=2) as ex:
            t_start = time.perf_counter() - t0
            warm(ex)
            r = run_sweep(st, specs, tmp / "dask", executor=ex, progress=False)
            rows.append(("dask LocalCluster (2), warm", r.n_computed, r.seconds))
        r = run_sweep(st, specs, tmp / "pool", workers=2, progress=False)
        rows.append(("resume, all stored", r.n_reused, r.seconds))
    base = rows[0][2]
    print(f"{'executor':>28} {'points':>7} {'seconds':>9} {'ms/point':>9} {'speed-up':>9}")
    for name, n, sec in rows:
        print(f"{name:>28} {n:>7d} {sec:>9.3f} {1e3 * sec / max(n, 1):>9.2f} "
              f"{base / sec:>9.2f}")
    print(f"(dask LocalCluster start-up: {t_start:.2f} s; 'cold' includes spawning the "
          "workers and their imports, 'warm' workers have imported qsa.spectra)")


def main():
    st = study()
    for label, specs in GRIDS.items():
        print(f"\nstudy: {st.__name__}, {label}: {specs}")
        bench(st, specs)


if __name__ == "__main__":
    main()
