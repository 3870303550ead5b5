"""Every bad input of the command line ends in one clear line and a documented exit code.

Exit codes (``qsa --help``): 0 done, 1 failure reported, 2 bad input, 130 interrupted,
141 output pipe closed. Most cases run in-process through ``qsa.cli.main`` (the
refusals happen before any work); the pipe, Ctrl-C and memory cases run ``python -m
qsa`` in a subprocess, as a user would.
"""

import json
import os
import pathlib
import re
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from qsa.cli import build_parser, main
from qsa.commands._errors import EXIT_CODES
from qsa.io import load

ROOT = pathlib.Path(__file__).resolve().parents[2]
CHA_RUN = ["flow", "cha", "--N", "40", "--t-final", "0.002", "--tol", "1e-3",
           "--no-progress"]


def run(capsys, *argv):
    """``(exit code, stdout, stderr)`` of ``qsa argv`` run in-process."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_error_line(err, *words):
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err and ": error: " in lines[0], err
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


def qsa_subprocess(args, cwd, **kwargs):
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
               MPLBACKEND="Agg", **kwargs.pop("env", {}))
    return subprocess.Popen([sys.executable, "-m", "qsa", *map(str, args)], cwd=cwd, env=env,
                            stdout=kwargs.pop("stdout", subprocess.PIPE),
                            stderr=subprocess.PIPE, **kwargs)


@pytest.fixture(scope="module")
def cha_checkpoint(tmp_path_factory):
    """A finished CHA run (N = 40, t = 0.002) and its checkpoint."""
    out = tmp_path_factory.mktemp("cha")
    assert main([*CHA_RUN, "--out", str(out / "run")]) == 0
    return out / "run" / "checkpoint.npz"


# ----------------------------------------------------------------- exit codes
def test_help_documents_the_exit_codes(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "exit codes:" in out
    for code in (0, 1, 2, 130):
        assert re.search(rf"^\s+{code}\s+\S", out, re.M), code
    assert set(EXIT_CODES) >= {0, 1, 2, 130}
    with pytest.raises(SystemExit):
        main(["flow", "cha", "--help"])
    assert "exit codes: 0 done, 1 failure reported, 2 bad input" in capsys.readouterr().out


def test_usage_error_is_one_line_and_exit_2(capsys):
    code, _, err = run(capsys, "flow", "cha", "--method", "rk4")
    assert code == 2
    assert_one_error_line(err, "qsa flow cha", "--method", "rk4")


# ------------------------------------------------------------- input files
def test_init_missing_file(tmp_path, capsys):
    code, _, err = run(capsys, *CHA_RUN, "--init", tmp_path / "missing.txt")
    assert code == 2
    assert_one_error_line(err, "--init", "missing.txt", "no such file")


def test_init_file_with_nan_names_the_file_and_the_row(tmp_path, capsys):
    t = 2 * np.pi * np.arange(50) / 50
    xy = np.column_stack([np.cos(t), np.sin(t)])
    xy[2, 1] = np.nan
    path = tmp_path / "curve.txt"
    np.savetxt(path, xy)
    code, _, err = run(capsys, *CHA_RUN, "--init", path)
    assert code == 2
    line = assert_one_error_line(err, str(path), "row 3", "NaN")
    assert "L_star" not in line
    path.write_text("1 2\n3 x\n")
    code, _, err = run(capsys, *CHA_RUN, "--init", path)
    assert code == 2
    assert_one_error_line(err, str(path), "cannot read")


def test_init_self_intersecting_limacon_is_refused(tmp_path, capsys):
    t = 2 * np.pi * np.arange(400) / 400
    r = 0.5 + np.cos(t)  # inner loop: turning number 2
    path = tmp_path / "limacon.txt"
    np.savetxt(path, np.column_stack([r * np.cos(t), r * np.sin(t)]))
    code, _, err = run(capsys, *CHA_RUN, "--init", path)
    assert code == 2
    assert_one_error_line(err, "intersects itself")
    from qsa import Curve, Fourier

    with pytest.raises(ValueError, match="intersect themselves.*turning number 1"):
        Curve.from_positions(r * np.cos(t), r * np.sin(t), Fourier(65))


# ------------------------------------------------------------------ resume
def test_resume_a_cha_checkpoint_with_flow_facet(cha_checkpoint, capsys):
    code, _, err = run(capsys, "flow", "facet", "--resume", cha_checkpoint, "--no-progress")
    assert code == 2
    assert_one_error_line(err, "a checkpoint of a CHA flow", "qsa flow cha --resume")


def test_resume_keeps_the_grid_and_the_model(cha_checkpoint, capsys):
    code, _, err = run(capsys, "flow", "cha", "--resume", cha_checkpoint, "--N", "80")
    assert code == 2
    assert_one_error_line(err, "--N 80", "N=40", "leave --N out")
    code, _, err = run(capsys, "flow", "cha", "--resume", cha_checkpoint, "--rho", "1.4")
    assert code == 2
    assert_one_error_line(err, "--rho 1.4", "rho=1.5")


def test_resume_to_a_time_before_the_checkpoint(cha_checkpoint, capsys):
    code, _, err = run(capsys, "flow", "cha", "--resume", cha_checkpoint, "--t-final", "0.001")
    assert code == 2
    assert_one_error_line(err, "--t-final 0.001", "t = 0.002", "continues forward")
    from qsa.flows import CHA, solve_flow

    with pytest.raises(ValueError, match="before the checkpoint's time"):
        solve_flow(CHA(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.5), None, 0.001,
                   tol=1e-3, resume=cha_checkpoint)


def test_resume_warns_about_initial_curve_options(cha_checkpoint, tmp_path, capsys):
    code, out, err = run(capsys, "flow", "cha", "--resume", cha_checkpoint, "--shape", "circle",
                         "--t-final", "0.003", "--checkpoint", tmp_path / "ck.npz",
                         "--no-progress", "--json")
    assert code == 0
    assert "warning: --shape ignored" in err and "Traceback" not in err
    s = json.loads(out)
    assert s["N"] == 40 and s["t_final"] == 0.003 and s["tol"] == 1e-3


def test_bare_resume_continues_the_checkpoint_in_out(cha_checkpoint, tmp_path, capsys):
    import shutil

    run_dir = tmp_path / "run"
    run_dir.mkdir()
    shutil.copy(cha_checkpoint, run_dir / "checkpoint.npz")
    code, out, err = run(capsys, "flow", "cha", "--resume", "--out", run_dir, "--t-final",
                         "0.003", "--no-progress", "--no-plots", "--json")
    assert code == 0, err
    s = json.loads(out)
    assert s["N"] == 40 and s["t_final"] == 0.003
    assert s["checkpoint"] == str(run_dir / "checkpoint.npz")


def test_bare_resume_needs_a_folder_or_a_file(tmp_path, capsys):
    code, _, err = run(capsys, "flow", "cha", "--resume", "--no-progress")
    assert code == 2
    assert_one_error_line(err, "--resume", "--resume FILE", "--out DIR")
    code, _, err = run(capsys, "flow", "cha", "--resume", "--out", tmp_path, "--no-progress")
    assert code == 2
    assert_one_error_line(err, "--resume", "checkpoint.npz", "no such file")


# ------------------------------------------------------------ bad numbers
@pytest.mark.parametrize("value", ["0", "-3", "1.5"])
def test_snapshots_must_be_at_least_two(value, capsys):
    code, _, err = run(capsys, *CHA_RUN, "--snapshots", value)
    assert code == 2
    assert_one_error_line(err, "--snapshots", value)


@pytest.mark.parametrize("argv", [
    ["flow", "cha", "--tol", "-1e-4"],
    ["equilibrium", "npulse", "--pulses", "3", "--alpha", "0.1", "--polish", "--tol", "-1e-4"],
    ["reproduce", "convergence", "--tol", "-1e-4"],
])
def test_negative_numbers_reach_the_option_and_are_rejected(argv, capsys):
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert_one_error_line(err, "--tol", "must be a positive number, got -1e-4")


def test_negative_numbers_in_exponent_form_parse():
    args = build_parser().parse_args(["equilibrium", "npulse", "--pulses", "3", "--alpha",
                                      "0.1", "--nu1", "-2.5E-3"])
    assert args.nu1 == -2.5e-3


# ------------------------------------------------------------------ outputs
@pytest.mark.parametrize("argv", [
    ["demo"],
    ["reproduce", "timesteps", "--tols", "1e-2", "--N", "32", "--t-final", "0.01"],
    ["reproduce", "convergence", "--Ns", "24", "48", "--t-final", "0.01"],
    [*CHA_RUN],
    ["sweep", "npulse", "--param", "alpha=0.2"],
])
def test_out_that_is_a_file_is_refused_before_any_work(argv, tmp_path, capsys):
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    t0 = time.perf_counter()
    code, out, err = run(capsys, *argv, "--out", blocker)
    assert code == 2 and out == ""
    assert_one_error_line(err, "--out", "is a file, not a folder")
    assert time.perf_counter() - t0 < 10  # the demo alone takes a minute
    assert blocker.read_text() == "not a folder"


def test_out_that_cannot_be_written_is_refused(tmp_path, capsys):
    if os.path.isdir("/sys") and not os.access("/sys", os.W_OK | os.X_OK):
        pytest.skip("no read-only folder to test with")
    target = "/sys/qsa-cannot-write" if os.path.isdir("/sys") else None
    if target is None or os.geteuid() != 0:
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        target = locked / "out"
        if os.access(locked, os.W_OK):
            pytest.skip("running with permissions that ignore the mode bits")
    code, _, err = run(capsys, "demo", "--out", target)
    assert code == 2
    assert_one_error_line(err, "--out", "cannot write")


def test_plot_into_a_missing_folder(tmp_path, capsys):
    code, _, err = run(capsys, *CHA_RUN, "--plot", tmp_path / "nodir" / "x.png")
    assert code == 2
    assert_one_error_line(err, "--plot", "nodir", "does not exist")


def test_plot_into_a_folder_and_without_extension(tmp_path, capsys):
    folder = tmp_path / "figs"
    folder.mkdir()
    code, _, err = run(capsys, *CHA_RUN, "--plot", folder)
    assert code == 2
    assert_one_error_line(err, "--plot", "is a folder; give a file name")
    code, _, err = run(capsys, *CHA_RUN, "--plot", tmp_path / "fig.xyz")
    assert code == 2
    assert_one_error_line(err, "unknown figure format .xyz")
    code, out, _ = run(capsys, *CHA_RUN, "--plot", tmp_path / "fig", "--json")
    assert code == 0
    assert json.loads(out)["figure"] == str(tmp_path / "fig.png")
    assert (tmp_path / "fig.png").read_bytes()[:4] == b"\x89PNG"
    assert not (tmp_path / "fig").exists()


def test_dask_without_a_scheduler_fails_fast(tmp_path, capsys):
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.perf_counter()
    code, _, err = run(capsys, "sweep", "npulse", "--param", "alpha=0.2", "--out",
                       tmp_path / "sw", "--dask", f"tcp://127.0.0.1:{port}")
    assert code == 2
    assert_one_error_line(err, "--dask", "no Dask scheduler there", "--dask-local")
    assert time.perf_counter() - t0 < 10


# ---------------------------------------------------------- silent changes
def test_splice_facets_changed_by_closure_are_reported(capsys):
    code, out, err = run(capsys, "equilibrium", "splice", "--angles", "90", "90", "90", "90",
                         "--facets", "1", "2", "3", "4", "--alpha", "0.1", "--json")
    assert code == 0
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "warning:" in lines[0]
    assert "--facets 1 2 3 4" in lines[0] and "2 3 2 3" in lines[0]
    assert json.loads(out)["params"]["facets"] == pytest.approx([2, 3, 2, 3])
    code, _, err = run(capsys, "equilibrium", "splice", "--angles", "120", "120", "120",
                       "--facets", "1", "1", "1", "--alpha", "0.1")
    assert code == 0 and "warning" not in err  # facets that close: nothing to say


def test_reproduce_resume_without_a_checkpoint_says_it_starts_afresh(tmp_path, capsys):
    code, out, err = run(capsys, "reproduce", "snowflake", "--resume", "--out", tmp_path,
                         "--t-final", "1e-6", "--kernel-length", "0.1", "--N", "300",
                         "--no-plots", "--json")
    assert code == 0, err
    warning = [line for line in err.splitlines() if "warning" in line]
    assert len(warning) == 1 and "no checkpoint" in warning[0] and "from t = 0" in warning[0]
    assert json.loads(out)["t_reached"] == pytest.approx(1e-6)


# ------------------------------------------------------ subprocess: pipes, signals
def test_output_piped_into_a_closed_reader_exits_quietly(tmp_path):
    proc = qsa_subprocess(["equilibrium", "circle", "--radius", "1", "--alpha", "0.1", "--N",
                           "33"], tmp_path)
    proc.stdout.close()  # as `| head -0` does: the reader is gone before qsa writes
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141
    assert "Traceback" not in err and "BrokenPipe" not in err and err.strip() == ""


def test_ctrl_c_saves_the_checkpoint_and_resume_finishes_the_run(tmp_path):
    argv = ["flow", "cha", "--N", "48", "--t-final", "0.08", "--tol", "1e-5"]
    proc = qsa_subprocess([*argv, "--out", "run", "--progress"], tmp_path)
    err = bytearray()

    def read_stderr():
        for chunk in iter(lambda: proc.stderr.read1(256), b""):
            err.extend(chunk)

    reader = threading.Thread(target=read_stderr)
    reader.start()
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:  # wait for t > 0.005
        m = re.findall(rb"t=([0-9.e+-]+)/", bytes(err))
        if m and float(m[-1]) > 0.005:
            break
        time.sleep(0.05)
    assert proc.poll() is None, bytes(err).decode()
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=120) == 130
    reader.join()
    text = bytes(err).decode()
    lines = [line for line in text.replace("\r", "\n").splitlines() if "qsa flow cha:" in line]
    assert len(lines) == 1 and "Traceback" not in text, text
    checkpoint = str(tmp_path / "run" / "checkpoint.npz")
    assert "interrupted at t = " in lines[0]
    assert lines[0].endswith("continue with: qsa flow cha --resume run/checkpoint.npz --out run")
    assert load(checkpoint).t[-1] < 0.08
    resumed = qsa_subprocess(["flow", "cha", "--resume", checkpoint, "--out", "resumed",
                              "--no-progress"], tmp_path)
    out, err2 = resumed.communicate(timeout=240)
    assert resumed.returncode == 0, err2.decode()
    assert main([*argv, "--out", str(tmp_path / "reference"), "--no-progress"]) == 0
    a, b = load(tmp_path / "resumed" / "result.npz"), load(tmp_path / "reference" / "result.npz")
    assert a.n_steps == b.n_steps and a.t[-1] == b.t[-1] == 0.08
    np.testing.assert_array_equal(a.states, b.states)  # the uninterrupted run, bit for bit


@pytest.mark.parametrize("argv", [
    ["flow", "facet", "--N", "10000000"],
    ["equilibrium", "npulse", "--pulses", "3", "--alpha", "0.1", "--N", "10000001"],
    ["spectrum", "npulse", "--pulses", "3", "--alpha", "0.1", "--N", "10000001"],
])
def test_runs_too_large_for_memory_are_refused_before_allocating(argv, tmp_path):
    t0 = time.perf_counter()
    proc = qsa_subprocess(argv, tmp_path, env={"QSA_MEMORY_LIMIT": "16G"})
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 2
    line = assert_one_error_line(err.decode(), "needs about", "16 GiB QSA_MEMORY_LIMIT",
                                 "smaller --N")
    needed = float(re.search(r"needs about ([0-9.e+]+) (GiB|TiB)", line).group(1))
    assert needed > 16
    assert time.perf_counter() - t0 < 60  # a refusal, not a minute of work and a segfault


def test_memory_estimate_refuses_a_moderate_run_under_a_small_limit(monkeypatch, capsys):
    monkeypatch.setenv("QSA_MEMORY_LIMIT", "500M")
    code, _, err = run(capsys, "flow", "facet", "--N", "20000", "--no-progress")
    assert code == 2
    assert_one_error_line(err, "N = 20000", "500 MiB QSA_MEMORY_LIMIT", "at most about N = ")
    code, _, err = run(capsys, "spectrum", "circle", "--radius", "1", "--alpha", "0.1",
                       "--N", "1001")
    assert code == 2
    assert_one_error_line(err, "the spectrum at N = 1001", "--k K")


def test_an_internal_error_is_one_line_and_exit_70(capsys, monkeypatch):
    import argparse

    from qsa.commands._errors import EXIT_INTERNAL, run_command

    def broken(args):
        return 1 / 0

    args = argparse.Namespace(qsa_prog="qsa test")
    monkeypatch.delenv("QSA_TRACEBACK", raising=False)
    assert run_command(broken, args) == EXIT_INTERNAL == 70
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("qsa test: error: internal error: ")
    assert "ZeroDivisionError" in err and "QSA_TRACEBACK=1" in err
    monkeypatch.setenv("QSA_TRACEBACK", "1")
    with pytest.raises(ZeroDivisionError):
        run_command(broken, args)
