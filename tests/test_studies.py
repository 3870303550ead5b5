"""qsa.studies: the helpers and bad input (the studies' numbers are asserted by the notebooks)."""

import numpy as np
import pytest

from qsa.studies import (
    STUDIES,
    circle_eigenvalues,
    circle_spectrum_study,
    flow_rate_study,
    mode_amplitude,
    npulse_study,
    splice_spectrum_study,
)
from tests.helpers import fitted_order


def test_mode_amplitude_of_a_polar_curve():
    th = 2 * np.pi * np.arange(400) / 400
    # nodes at non-uniform angles: the trapezoid rule is in phi, not in the index
    th = th + 0.05 * np.sin(th)
    r = 1 + 0.01 * np.cos(3 * th + 0.4) + 0.002 * np.sin(2 * th)
    x, y = r * np.cos(th) + 0.3, r * np.sin(th) - 0.2
    assert mode_amplitude(x, y, 3) == pytest.approx(0.01, rel=1e-3)
    assert mode_amplitude(x, y, 2) == pytest.approx(0.002, rel=1e-2)
    assert mode_amplitude(x, y, 5) < 1e-5


def test_circle_eigenvalues_formula():
    lam = circle_eigenvalues(1.0, 0.1, kstar=5.0, beta=5.0, kmax=3)
    # W''(1) = (6 - 30 + 25)/2 = 1/2; lambda_k = -(k^2-1)^2 (alpha^2 k^2 + 1/2)
    np.testing.assert_allclose(lam, [-(0.5) - 10 * np.pi, 0.0, -9 * 0.54, -64 * 0.59])


def test_circle_spectrum_study_fd_second_order():
    Ns = [64, 128, 256]
    errs = [circle_spectrum_study(N=N, fd=True, kmax=4)["max_rel_error"] for N in Ns]
    assert abs(fitted_order(Ns, errs) - 2) < 0.1


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="N must be an integer >= 8"):
        npulse_study(N=4)
    with pytest.raises(ValueError, match="N: finite differences need an explicit N"):
        npulse_study(fd=True)
    with pytest.raises(ValueError, match="angles must be comma-separated"):
        splice_spectrum_study(angles="120;120;120")
    with pytest.raises(ValueError, match="mode must be >= 2"):
        flow_rate_study(mode=1)
    with pytest.raises(ValueError, match="kmax=20 needs N >= 41"):
        circle_spectrum_study(N=33, kmax=20)


def test_registry_and_defaults():
    import inspect

    for name, fn in STUDIES.items():
        params = inspect.signature(fn).parameters.values()
        assert all(p.default is not p.empty for p in params), name
    r = npulse_study(n_pulses=3.0, alpha=0.2)  # a float count from a "3.0" spec is accepted
    assert r["n_nodes"] % 2 == 1 and r["closure"] < 1e-10


def test_cli_plot_default_column(tmp_path, capsys):
    from qsa.cli import main

    png = tmp_path / "c.png"
    assert main(["sweep", "circle-spectrum", "--param", "N=33,41", "--out", str(tmp_path / "o"),
                 "--workers", "1", "--plot", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG" and "2 computed" in capsys.readouterr().out
