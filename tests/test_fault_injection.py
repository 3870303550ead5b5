"""Kill a running flow (SIGKILL) and resume it from its checkpoint; damaged checkpoints."""

import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from qsa.flows import CHA, FacetingFlow, solve_flow
from qsa.io import load_npz
from qsa.paper import CONVERGENCE

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAPER_CHA = CONVERGENCE.model_params()  # the appendix's convergence example
SCRIPT = textwrap.dedent("""
    import sys
    from qsa.flows import CHA, solve_flow
    from qsa.paper import CONVERGENCE
    solve_flow(CHA(**{cha}), CONVERGENCE.samples(800),
               {T}, N=48, tol={tol}, checkpoint=sys.argv[1], checkpoint_interval=0,
               t_eval=[{T}])
""")
T, TOL = 0.08, 1e-5


def paper_samples(M=800):
    return CONVERGENCE.samples(M)


def test_sigkill_then_resume_gives_the_uninterrupted_result(tmp_path):
    path = tmp_path / "run.npz"
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT.format(cha=PAPER_CHA, T=T, tol=TOL),
                             str(path)], env=env, cwd=tmp_path)
    t_killed = None
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if path.exists():
                _, meta = load_npz(path)  # atomic writes: never half a file
                if meta["integrator"]["n_steps"] >= 30:
                    proc.send_signal(signal.SIGKILL)
                    t_killed = meta["integrator"]["t"]
                    break
            time.sleep(0.02)
    finally:
        if proc.poll() is None and t_killed is None:
            proc.kill()
        proc.wait()
    assert t_killed is not None and proc.returncode == -signal.SIGKILL
    _, meta = load_npz(path)  # the file left by the killed run is readable
    assert meta["status"] == "running" and meta["integrator"]["t"] < T
    resumed = solve_flow(CHA(**PAPER_CHA), None, T, tol=TOL, resume=path, t_eval=[T])
    full = solve_flow(CHA(**PAPER_CHA), paper_samples(), T, N=48, tol=TOL, t_eval=[T])
    assert resumed.success and resumed.n_steps == full.n_steps
    np.testing.assert_allclose(resumed.states[-1], full.states[-1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(resumed.energy_steps, full.energy_steps, rtol=1e-13)


@pytest.mark.parametrize("method", ["be", "bdf2"])
def test_stop_and_resume_equals_uninterrupted(tmp_path, method):
    model = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=7.0)
    th = 2 * np.pi * np.arange(400) / 400
    r = 1.3 * (1 + 0.1 * np.cos(3 * th))
    init = (r * np.cos(th), r * np.sin(th))
    path = tmp_path / f"{method}.npz"
    full = solve_flow(model, init, 5e-3, N=48, tol=1e-4, method=method)
    part = solve_flow(model, init, 5e-3, N=48, tol=1e-4, method=method, checkpoint=path,
                      callback=lambda t, y, s: t > 2e-3)
    assert part.status == 1 and part.t[-1] < 5e-3
    res = solve_flow(model, None, 5e-3, tol=1e-4, method=method, resume=path)
    assert res.n_steps == full.n_steps and res.n_newton == full.n_newton
    np.testing.assert_allclose(res.states, full.states, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(res.t, full.t)


def test_damaged_or_foreign_checkpoint_raises_value_error(tmp_path):
    model = CHA(eps=0.1, beta=1.0, rho=1.2)
    path = tmp_path / "c.npz"
    solve_flow(model, paper_samples(), 1e-3, N=40, tol=1e-3, checkpoint=path)
    data = path.read_bytes()
    bad = tmp_path / "bad.npz"
    bad.write_bytes(data[: len(data) // 3])
    with pytest.raises(ValueError, match="corrupt or truncated"):
        solve_flow(model, None, 2e-3, tol=1e-3, resume=bad)
    mid = len(data) // 2
    bad.write_bytes(data[:mid] + bytes([data[mid] ^ 0x5A]) + data[mid + 1 :])
    with pytest.raises(ValueError, match="corrupt"):
        solve_flow(model, None, 2e-3, tol=1e-3, resume=bad)
    with pytest.raises(ValueError, match="tol"):
        solve_flow(model, None, 2e-3, tol=1e-4, resume=path)
    with pytest.raises(ValueError, match="model"):
        solve_flow(CHA(eps=0.2, beta=1.0, rho=1.2), None, 2e-3, tol=1e-3, resume=path)
