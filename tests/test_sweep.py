"""qsa.sweep: grid specs, executors (process pool, Dask), resumption after SIGKILL, damage."""

import json
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from qsa.studies import STUDIES, npulse_study
from qsa.sweep import (
    ParameterGrid,
    SweepWarning,
    load_point,
    parse_param,
    point_key,
    read_table,
    run_sweep,
)
from tests.helpers import slow_study

ROOT = Path(__file__).resolve().parents[1]
# 16 points of the headline study (4 alphas x 4 pulse counts, all existing: N alpha < 1),
# on Fourier(121): resolved to a relative residual < 1e-6 at these alphas
GRID16 = ["alpha=0.16:0.19:4", "n_pulses=2,3,4,5", "N=121"]


def headline_study():
    """The spectrum study once qsa.spectra provides it, else the N-pulse study."""
    try:
        from qsa import spectra

        if hasattr(spectra, "spectrum"):
            return STUDIES["spectrum"]
    except ImportError:  # pragma: no cover
        pass
    return npulse_study


def failing_study(x=0.0):
    if x > 0.5:
        raise ValueError(f"x={x} is out of range")
    return {"y": 2 * x, "vec": np.arange(3) * x}


def numeric_table(path):
    rows = read_table(path)
    return rows


def assert_same_table(a, b, rtol=1e-12):
    ra, rb = read_table(a), read_table(b)
    assert [list(r) for r in ra] == [list(r) for r in rb]
    for x, y in zip(ra, rb, strict=True):
        for k in x:
            if isinstance(x[k], float):
                assert y[k] == pytest.approx(x[k], rel=rtol, abs=1e-300), k
            else:
                assert x[k] == y[k], k


# -------------------------------------------------------------- grid specs
def test_parse_param_forms():
    assert parse_param("alpha=0.05:0.3:11")[1] == pytest.approx(np.linspace(0.05, 0.3, 11))
    assert parse_param("alpha=0.05:0.3:11")[1][1] == 0.075  # no last-bit noise
    assert parse_param("N=2,3,4") == ("N", [2, 3, 4])
    assert parse_param("fd=true") == ("fd", [True])
    assert parse_param(" x = 1.5, 2") == ("x", [1.5, 2])
    g = ParameterGrid.parse(["a=1,2", "b=0:1:3"])
    assert len(g) == 6 and g.points()[0] == {"a": 1, "b": 0.0} and g.points()[-1]["b"] == 1.0
    assert ParameterGrid.from_dict({"a": np.arange(2), "b": 3.0}).points() == [
        {"a": 0, "b": 3.0}, {"a": 1, "b": 3.0}]


@pytest.mark.parametrize("spec, match", [
    ("alpha", "NAME="), ("=1,2", "valid parameter name"), ("alpha=", "no values"),
    ("alpha=0:1", "start:stop:num"), ("alpha=0:1:x", "integer"), ("alpha=0:1:0", "num >= 1"),
    ("a=1,,2", "empty value"), ("2a=1", "valid parameter name"),
])
def test_parse_param_errors(spec, match):
    with pytest.raises(ValueError, match=match):
        parse_param(spec)


def test_bad_arguments(tmp_path):
    with pytest.raises(ValueError, match="given twice"):
        ParameterGrid.parse(["a=1", "a=2"])
    with pytest.raises(ValueError, match="not parameters of"):
        run_sweep(npulse_study, ["alhpa=0.1"], tmp_path)
    with pytest.raises(ValueError, match="on_corrupt"):
        run_sweep(npulse_study, ["alpha=0.1"], tmp_path, on_corrupt="ignore")
    with pytest.raises(ValueError, match="workers"):
        run_sweep(npulse_study, ["alpha=0.1"], tmp_path, workers=0)
    run_sweep(failing_study, ["x=0.1"], tmp_path / "f", workers=1)
    with pytest.raises(ValueError, match="holds a sweep of"):
        run_sweep(npulse_study, ["alpha=0.1"], tmp_path / "f", workers=1)


# ------------------------------------------------------------- executors
def test_dask_local_cluster_equals_process_pool(tmp_path, capsys):
    """The 16-point headline sweep: LocalCluster(2 worker processes) == process pool."""
    LocalCluster = pytest.importorskip(
        "distributed", reason="dask.distributed is not installed (the 'dask' extra)").LocalCluster

    from qsa.cli import main
    from qsa.sweep import dask_executor

    study = headline_study()
    pool = run_sweep(study, GRID16, tmp_path / "pool", workers=2)
    assert pool.success and pool.n_computed == 16, pool.message
    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                      dashboard_address=None) as cluster:
        with dask_executor(address=cluster.scheduler_address) as ex:
            dsk = run_sweep(study, GRID16, tmp_path / "dask", executor=ex)
        # the CLI on the same cluster: qsa sweep ... --dask ADDRESS
        assert main(["sweep", "npulse", "--param", "alpha=0.1,0.2", "--out",
                     str(tmp_path / "cli"), "--dask", cluster.scheduler_address, "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["n_computed"] == 2
    assert dsk.success and dsk.n_computed == 16
    assert_same_table(pool.table_path, dsk.table_path)
    # the arrays stored per point agree as well
    for i in (0, 7, 15):
        a, b = pool.arrays(i), dsk.arrays(i)
        assert sorted(a) == sorted(b)
        for k in a:
            np.testing.assert_allclose(a[k], b[k], rtol=1e-12, atol=1e-300)
    # the headline numbers: every point is an equilibrium; with the spectrum, the kernel is the
    # three rigid motions and more pulses mean more unstable modes at fixed alpha
    assert all(r["relative_residual"] < 1e-5 for r in pool.rows)
    if study is STUDIES["spectrum"]:
        assert all(r["n_kernel"] == 3 for r in pool.rows)
        for a in {r["alpha"] for r in pool.rows}:
            counts = [r["n_unstable"] for r in pool.rows if r["alpha"] == a]
            assert counts[0] == 0 and counts[1] == 2 and np.all(np.diff(counts) > 0), counts


def test_serial_executor_and_failed_points(tmp_path):
    res = run_sweep(failing_study, ["x=0:1:5"], tmp_path, workers=1)
    assert not res.success and res.n_failed == 2
    np.testing.assert_array_equal(res.column("success"), [1, 1, 1, 0, 0])
    assert "x=0.75 is out of range" in res.rows[3]["message"]
    assert np.isnan(res.column("y")[4]) and res.column("y")[2] == 1.0
    np.testing.assert_array_equal(res.arrays(2)["vec"], [0.0, 0.5, 1.0])
    # failed points are stored results: a rerun computes nothing
    again = run_sweep(failing_study, ["x=0:1:5"], tmp_path, workers=1)
    assert again.n_computed == 0 and again.n_reused == 5
    assert again.table_path.read_bytes() == res.table_path.read_bytes()


# ------------------------------------------------------------ resumption
def _stored(points):
    return sorted(points.glob("*.json")) if points.exists() else []


def test_sigkill_then_resume_computes_only_missing_points(tmp_path):
    out = tmp_path / "sw"
    specs = ["alpha=0.08:0.2:3", "n_pulses=2,3,4", "delay=0.4"]
    code = ("import sys; from tests.helpers import slow_study; from qsa.sweep import run_sweep;"
            f"run_sweep(slow_study, {specs!r}, {str(out)!r}, workers=2, progress=False)")
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60
        while len(_stored(out / "points")) < 3:
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() < deadline, "the sweep stored no points"
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its pool workers
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    done = {p.stem: p.stat().st_mtime_ns for p in _stored(out / "points")}
    assert 3 <= len(done) < 9, "killed too late to test resumption"
    assert not (out / "results.csv").exists()

    (out / "points" / ".deadbeef.json.abc.tmp").write_bytes(b"half")  # as a kill can leave
    res = run_sweep(slow_study, specs, out, workers=2)
    assert res.success and res.n_points == 9
    assert not list((out / "points").glob(".*.tmp"))
    assert res.n_reused == len(done) and res.n_computed == 9 - len(done)
    # the finished points were not touched, the missing ones came from this run's workers
    for key, mtime in done.items():
        assert (out / "points" / f"{key}.json").stat().st_mtime_ns == mtime
    pids = {r["pid"] for r, k in zip(res.rows, res.keys, strict=True) if k not in done}
    assert os.getpid() not in pids
    # and the table is the one an uninterrupted sweep gives (pids aside)
    full = run_sweep(slow_study, specs[:2] + ["delay=0.0"], tmp_path / "full", workers=1)
    for a, b in zip(res.rows, full.rows, strict=True):
        for k in ("alpha", "n_pulses", "success", "n_nodes", "residual", "L", "L_star",
                  "energy"):
            assert a[k] == b[k], k


def test_damaged_point_files_are_recomputed_or_raise(tmp_path):
    specs = ["alpha=0.1,0.2", "n_pulses=3"]
    first = run_sweep(npulse_study, specs, tmp_path, workers=1)
    pts = tmp_path / "points"
    k0, k1 = first.keys
    npz = pts / f"{k0}.npz"
    npz.write_bytes(npz.read_bytes()[:100])  # truncated
    (pts / f"{k1}.json").write_text('{"params": ')  # not JSON
    with pytest.raises(ValueError, match=f"point file .*{k0}.json.*unreadable.*checksum"):
        run_sweep(npulse_study, specs, tmp_path, workers=1, on_corrupt="raise")
    with pytest.warns(SweepWarning, match="recomputing") as rec:
        again = run_sweep(npulse_study, specs, tmp_path, workers=1)
    assert len(rec) == 2
    assert again.n_computed == 2 and again.n_recomputed_corrupt == 2
    assert again.table_path.read_bytes() == first.table_path.read_bytes()
    # repaired: nothing left to do
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert run_sweep(npulse_study, specs, tmp_path, workers=1).n_computed == 0
    # a point file whose key does not match its parameters is damage too
    meta = json.loads((pts / f"{k0}.json").read_text())
    meta["params"]["alpha"] = 0.3
    (pts / f"{k0}.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match="stored for params"):
        load_point(pts, k0, first.study, {"alpha": 0.1, "n_pulses": 3})


def test_point_files_have_no_pickle(tmp_path):
    res = run_sweep(npulse_study, ["alpha=0.1"], tmp_path, workers=1)
    key = point_key(res.study, {"alpha": 0.1})
    with np.load(tmp_path / "points" / f"{key}.npz", allow_pickle=False) as z:
        assert sorted(z.files) == ["g", "kappa"] and z["kappa"].dtype == float
    meta = json.loads((tmp_path / "points" / f"{key}.json").read_text())
    assert meta["params"] == {"alpha": 0.1} and meta["results"]["converged"] is True


# ------------------------------------------------------------- CLI, plot
def test_cli_json_plot_and_resume(tmp_path, capsys):
    from qsa.cli import main

    argv = ["sweep", "npulse", "--param", "alpha=0.1:0.3:3", "--param", "n_pulses=3,4",
            "--out", str(tmp_path / "o"), "--workers", "1", "--json",
            "--plot", str(tmp_path / "p.png")]
    assert main(argv) == 1  # 4 pulses at alpha = 0.3 do not exist: a failed point
    s = json.loads(capsys.readouterr().out)
    assert s["n_points"] == 6 and s["n_failed"] == 1 and s["n_computed"] == 6
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    rows = read_table(tmp_path / "o" / "results.csv")
    bad = [r for r in rows if not r["success"]]
    assert len(bad) == 1 and bad[0]["n_pulses"] == 4 and "N alpha < 1" in bad[0]["message"]
    assert main(argv[:-2]) == 1
    assert json.loads(capsys.readouterr().out)["n_reused"] == 6
    assert main(["sweep", "npulse", "--out", str(tmp_path / "x")]) == 2
    assert "--param" in capsys.readouterr().err


def test_plot_sweep(tmp_path):
    from qsa.plotting import plot_sweep

    res = run_sweep(npulse_study, ["alpha=0.1:0.2:3", "n_pulses=2,3"], tmp_path, workers=1)
    fig = plot_sweep(res, "alpha", "L")
    ax = fig.axes[0]
    assert len(ax.lines) == 2 and ax.get_xlabel() == "alpha"
    np.testing.assert_allclose(ax.lines[0].get_ydata(), res.column("L")[::2])
    with pytest.raises(ValueError, match="column 'nope'"):
        plot_sweep(res, "alpha", "nope")
