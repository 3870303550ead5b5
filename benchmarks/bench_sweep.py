"""Cost of ``qsa.sweep``: the same sweep on each executor, and the cost of resuming.

The sweep is the headline study (``spectrum_study`` when ``qsa.spectra`` provides it,
otherwise ``npulse_study``) on ``alpha = 0.06 .. 0.16`` x ``n_pulses = 2 .. 5`` (24
points), run in-process (``workers=1``), on a local process pool (2 workers) and on a
Dask ``LocalCluster`` (2 worker processes; cluster start-up timed separately). Then a
second run over the finished directory (every point reused) measures the overhead of
checking the stored points.

Prints a table: executor, points computed, wall seconds, ms per point, speed-up over
in-process. Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_sweep.py``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from qsa.studies import STUDIES
from qsa.sweep import dask_executor, run_sweep

SPECS = ["alpha=0.06:0.16:6", "n_pulses=2,3,4,5"]


def study():
    try:
        from qsa import spectra

        if hasattr(spectra, "spectrum"):
            return STUDIES["spectrum"]
    except ImportError:
        pass
    return STUDIES["npulse"]


def main():
    st = study()
    print(f"study: {st.__name__}, grid {SPECS}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        r = run_sweep(st, SPECS, tmp / "serial", workers=1, progress=False)
        rows.append(("in-process", r.n_computed, r.seconds))
        r = run_sweep(st, SPECS, tmp / "pool", workers=2, progress=False)
        rows.append(("process pool (2)", r.n_computed, r.seconds))
        t0 = time.perf_counter()
        with dask_executor(n_workers=2) as ex:
            t_start = time.perf_counter() - t0
            r = run_sweep(st, SPECS, tmp / "dask", executor=ex, progress=False)
            rows.append(("dask LocalCluster (2)", r.n_computed, r.seconds))
        r = run_sweep(st, SPECS, tmp / "pool", workers=2, progress=False)
        rows.append(("resume, all stored", r.n_reused, r.seconds))
    base = rows[0][2]
    print(f"{'executor':>24} {'points':>7} {'seconds':>9} {'ms/point':>9} {'speed-up':>9}")
    for name, n, sec in rows:
        print(f"{name:>24} {n:>7d} {sec:>9.3f} {1e3 * sec / max(n, 1):>9.2f} "
              f"{base / sec:>9.2f}")
    print(f"(dask LocalCluster start-up: {t_start:.2f} s, not included above)")


if __name__ == "__main__":
    main()
