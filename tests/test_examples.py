"""Every script in examples/ asserted on its headline numbers (STYLE.md, tests 7)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def assert_figure(fig, lines):
    """The example's figure (shown by the documentation's gallery) draws and is labelled."""
    (ax,) = fig.axes
    assert len(ax.get_lines()) == lines
    assert ax.get_xlabel() and ax.get_ylabel()
    fig.canvas.draw()


def test_examples_listed_in_readme():
    readme = (EXAMPLES / "README.md").read_text()
    scripts = sorted(p.stem for p in EXAMPLES.glob("ex[0-9][0-9]_*.py"))
    assert len(scripts) >= 3
    assert all(f"{name}.py" in readme for name in scripts)


def test_ex01_circle_spectrum():
    mod = load("ex01_circle_spectrum")
    out = mod.main()
    # closed form: lambda_0 = -W''(1) - 2 pi beta, lambda_2 = -9 (4 alpha^2 + W''(1)),
    # W''(1) = (6 - 6 kstar + kstar^2)/2 = 0.5 for kstar = 5
    assert out["lambda_0"] == pytest.approx(-0.5 - 10 * np.pi)
    assert out["lambda_2"] == pytest.approx(-9 * (0.04 + 0.5))
    assert max(out["fourier_max_rel_error"]) < 1e-9
    assert out["fourier_n_unstable"] == 0 and out["fourier_n_kernel"] == 2
    assert out["fd_order"] == pytest.approx(2.0, abs=0.2)
    assert out["fd_max_rel_error"][-1] < 0.02
    assert_figure(mod.figure(out), lines=3)


def test_ex02_npulse_family():
    mod = load("ex02_npulse_family")
    out = mod.main()
    rows = out["rows"]
    assert [r["n_pulses"] for r in rows] == [2, 3, 4, 5, 6]
    assert all(r["success"] for r in rows)
    assert all(r["relative_residual"] < 1e-8 and r["closure"] < 1e-10 for r in rows)
    # nu1 = 0, symmetric quartic well: L = 4 pi / kstar for every N; L* > L, growing with N
    assert np.allclose([r["L"] for r in rows], 4 * np.pi / 5.0, rtol=1e-10)
    L_star = np.array([r["L_star"] for r in rows])
    assert np.all(L_star >= rows[0]["L"]) and np.all(np.diff(L_star) > 0)
    # the 2-pulse is stable; each further pulse adds two coarsening directions
    assert [r["n_unstable"] for r in rows] == [0, 2, 4, 6, 8]
    assert all(r["n_kernel"] == 3 for r in rows)
    assert_figure(mod.figure(out), lines=2)


def test_ex03_splice_dichotomy():
    mod = load("ex03_splice_dichotomy")
    out = mod.main()
    rows = out["rows"]
    assert all(r["success"] for r in rows)
    # 3 corners = 6 fronts: 2 * 3 - 1 small eigenvalues, separated from the O(1) rest
    assert all(r["n_small"] == 5 for r in rows)
    gaps = [r["gap_ratio"] for r in rows]
    assert gaps[0] > 20 and np.all(np.diff(gaps) > 0)
    assert all(-80 < r["first_fast"] < -60 for r in rows)
    # the cluster shrinks like exp(-kstar d_min / (sqrt 2 alpha))
    assert out["predicted_slope"] == pytest.approx(-5.0 * (2 * np.pi / 15) / np.sqrt(2))
    assert out["slope"] == pytest.approx(out["predicted_slope"], rel=0.1)
    ratios = [r["max_small"] / r["prediction"] for r in rows]
    assert max(ratios) / min(ratios) < 2
    assert_figure(mod.figure(out), lines=2)
