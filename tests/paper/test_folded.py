"""Folded-state analysis (qsa.paper.folded): polish, spectrum with its kernel, DAE rate.

The state is the reference CHA equilibrium (appendix parameters, l* = 0.5) sampled at
160 nodes, as a flow's final nodes would be. The resolution tests use a zipped dumbbell
at l* = 0.05 polished on Fourier(201), 1.4 nodes per l*.
"""

import json

import numpy as np
import pytest

from qsa.paper.folded import UnderResolvedWarning, folded_equilibrium, kernel_resolution
from tests.helpers import CHA_REF as REF
from tests.helpers import folded_nodes as nodes

RHO = 1.5


def analyse(x, y, **options):
    return folded_equilibrium(x, y, eps=REF["eps"], beta=REF["beta"], rho=RHO,
                              L0=REF["L_star"] / RHO, A0=REF["A0"], l_star=REF["l_star"],
                              a=REF["a"], **options)


@pytest.fixture(scope="module")
def fe():
    return analyse(*nodes(noise=2e-3))


def test_polish_spectrum_and_flow_rate(fe):
    assert fe.polished.success and fe.relative_residual <= 1e-9
    assert fe.N == 161
    sp = fe.spectrum
    assert sp.n_kernel == 3                       # the rigid motions, recognised
    assert np.all(np.abs(sp.eigenvalues[sp.is_kernel]) <= sp.kernel_tol)
    assert fe.n_unstable == int(np.sum(sp.eigenvalues[~sp.is_kernel] > 0))
    assert not np.any(sp.is_kernel[fe.slowest])
    # the DAE decays along the slowest decaying mode at its eigenvalue, within 1%
    assert fe.rate["success"]
    assert fe.rate["eigenvalue"] == max(v for v in sp.eigenvalues[~sp.is_kernel] if v < 0)
    assert fe.rate["relative_error"] <= 0.01
    # the error estimate (extrapolation + fit window) covers the measured difference
    assert abs(fe.rate["measured_rate"] - fe.rate["eigenvalue"]) <= fe.rate["rate_error"]
    s = json.loads(json.dumps(fe.summary()))
    assert s["n_kernel"] == 3 and s["rate"]["relative_error"] <= 0.01
    assert s["params"]["L_star"] == pytest.approx(REF["L_star"], rel=1e-14)
    # 7.8 nodes per l*: the grid resolves the state, kernel and all (no refinement)
    assert fe.resolved is True and fe.refinements == [] and s["resolved"] is True
    assert s["unresolved_reason"] is None and s["kernel_ratio"] < 1e-6


def test_slowest_modes_figure(fe):
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from qsa.plotting.simulations import folded_modes_figure

    fig = folded_modes_figure([fe], n_modes=2)
    lcs = [c for ax in fig.axes for c in ax.collections if isinstance(c, LineCollection)]
    assert len(lcs) == 2
    phi = fe.spectrum.eigenvectors[:, fe.slowest[0]]
    assert np.allclose(lcs[0].get_array(), phi / np.abs(phi).max())
    # one panel of 3.2 x 3.2 inches per mode (the figure is not stretched n_modes times)
    assert np.allclose(fig.get_size_inches(), (2 * 3.2, 3.2))
    plt.close(fig)


def test_failed_polish_reported_without_spectrum():
    fe = analyse(*nodes(noise=2e-3), maxiter=1, rate_check=False)
    assert not fe.polished.success and fe.spectrum is None and not fe.success
    s = json.loads(json.dumps(fe.summary()))
    assert s["polish_success"] is False and "n_unstable" not in s
    assert np.all(np.isfinite(fe.curve.kappa))


def test_bad_nodes():
    with pytest.raises(ValueError, match="x, y"):
        analyse(np.zeros(10), np.zeros(11))
    from qsa import Curve, FiniteDifference

    with pytest.raises(ValueError, match="x: a Curve guess must be on a Fourier grid"):
        analyse(Curve.circle(1.0, FiniteDifference(40)), None)
    with pytest.raises(ValueError, match="kernel_resolve"):
        analyse(*nodes(), kernel_resolve=-1e-3)
    with pytest.raises(ValueError, match="spectrum_options"):
        analyse(*nodes(), spectrum_options=8)


def test_curve_guess_without_spectrum(fe):
    """A polished curve is taken as it is (no resampling of its nodes), no spectrum."""
    again = analyse(fe.curve, None, with_spectrum=False)
    assert again.guess is fe.curve and again.spectrum is None and not again.success
    assert again.polished.success and again.polished.n_newton <= 1
    assert again.polished.energy.energy(again.curve) == pytest.approx(
        fe.energy.energy(fe.curve), rel=1e-13)


@pytest.mark.slow
def test_reproduce_folded_table_t1(tmp_path):
    """The full f:fold reproduction: every final state polished, kernel 3, rate within 1%."""
    from qsa.cli import main

    assert main(["reproduce", "folded", "--out", str(tmp_path), "--no-progress",
                 "--no-plots", "--json"]) == 0
    s = json.loads((tmp_path / "folded.json").read_text())
    assert not s["failed"] and len(s["equilibria"]) == 3
    for e in s["equilibria"]:
        assert e["relative_residual"] <= 1e-9 and e["n_kernel"] == 3
        assert e["rate"]["relative_error"] <= 0.01


def test_registration_recovers_a_parameter_shift_under_a_rigid_motion():
    from qsa.paper.folded import _registration, _shift

    n = 101
    t = 2 * np.pi * np.arange(n) / n
    r = 1 + 0.2 * np.cos(3 * t) + 0.1 * np.sin(5 * t)
    X, Y = r * np.cos(t), r * np.sin(t)
    sigma = 0.37                                   # nodes
    xs, ys = _shift(np.vstack([X, Y]), sigma)      # X(s + sigma h), exact for this band
    ang = 0.3
    x = np.cos(ang) * xs - np.sin(ang) * ys + 2.0
    y = np.sin(ang) * xs + np.cos(ang) * ys - 1.0
    # the nodes (x, y) sit at s + sigma h: shifting them back by -sigma matches (X, Y)
    assert _registration(x, y, X, Y) == pytest.approx(-sigma, abs=1e-6)
    f = np.cos(2 * t) + 0.5 * np.sin(7 * t)
    assert np.allclose(_shift(_shift(f, sigma), -sigma), f)
    assert np.allclose(_shift(f, 1.0), np.roll(f, -1))


def test_sheet_pairs_of_the_polished_curve(fe):
    """Sheet pairs: those of the polished nodes, against d* = l* sqrt(a^2 + 1/2)."""
    from qsa.flows.analysis import paired_sheets

    d_star = REF["l_star"] * np.sqrt(REF["a"] ** 2 + 0.5)
    assert fe.separation_target == pytest.approx(d_star, rel=1e-15)
    expected = paired_sheets(*fe.curve.positions(), d_star).to_dict()
    s = json.loads(json.dumps(fe.summary()))
    assert s["sheets"]["n_pairs"] == expected["n_pairs"]
    assert s["sheets"]["target"] == pytest.approx(d_star, rel=1e-15)
    assert s["sheets"]["separations"] == pytest.approx(expected["separations"], rel=1e-15)


@pytest.fixture(scope="module")
def zipped():
    """A paired-sheet CHA equilibrium on Fourier(201), 1.4 nodes per l*: V^n is resolved
    (4e-11 of its scale), the rigid motions' eigenvalues are not (up to 0.16, against a
    slowest other |lambda| of 0.36)."""
    from qsa.paper.near_contact import paired_dumbbell

    st = paired_dumbbell(0.05, N=201, t_flow=0.5)
    assert st.polished.success and st.relative_residual <= 1e-9 and st.N == 201
    return st


def analyse_zipped(st, **options):
    p = st.params
    return folded_equilibrium(st.curve, None, eps=p["eps"], beta=p["beta"], rho=p["rho"],
                              L0=p["L0"], A0=p["A0"], l_star=p["l_star"], a=p["a"],
                              rate_check=False, **options)


def test_unresolved_kernel_at_max_N_is_flagged(zipped):
    with pytest.warns(UnderResolvedWarning, match="rigid motions' eigenvalues.*max_N = 201"):
        fe = analyse_zipped(zipped, max_N=201)
    assert fe.polished.success and fe.polished.residual <= 1e-9 * fe.polished.residual_scale
    assert fe.N == 201 and fe.refinements == [] and fe.spectrum is not None
    kr = kernel_resolution(fe.spectrum)
    assert kr["kernel_level"] == fe.spectrum.kernel_tol and kr["ratio"] > 0.1
    assert fe.resolved is False and not fe.success
    s = json.loads(json.dumps(fe.summary()))
    assert s["resolved"] is False and s["success"] is False
    assert "Fourier(401) is beyond max_N = 201" in s["unresolved_reason"]
    assert s["kernel_ratio"] == pytest.approx(kr["ratio"], rel=1e-12)
    from qsa.commands.reproduce_folded import summary_line

    assert "NOT RESOLVED: Fourier(201) does not resolve the state" in summary_line(s)
    # without the kernel test the V^n test alone passes this grid
    fe0 = analyse_zipped(zipped, max_N=201, kernel_resolve=None)
    assert fe0.resolved is True and fe0.N == 201


def test_unresolved_kernel_refines_the_grid(zipped):
    # the 8 eigenvalues nearest 0 (shift-invert) on each grid: the kernel and 5 slow ones
    fe = analyse_zipped(zipped, spectrum_options={"k": 8})
    assert fe.spectrum.method == "shift-invert" and fe.spectrum.eigenvalues.size == 8
    assert fe.N == 401 and fe.resolved is True and fe.unresolved_reason is None
    assert fe.polished.success and fe.polished.residual <= 1e-9 * fe.polished.residual_scale
    (ref,) = fe.refinements
    assert ref["reason"] == "kernel" and ref["N"] == 401 and ref["kernel_ratio"] > 0.1
    kr = kernel_resolution(fe.spectrum)
    assert kr["ratio"] < 1e-5 and fe.spectrum.n_kernel == 3
    # the slowest eigenvalue moved by about the coarse kernel's level (0.16): 0.359 -> 0.333
    assert abs(kr["slowest"] - ref["slowest"]) < max(np.abs(ref["kernel_eigenvalues"]))
    assert kr["slowest"] == pytest.approx(0.3325, rel=1e-3)


def test_unresolved_residual_at_max_N_is_flagged():
    """On 101 nodes the reference state polishes to max|V^n| 3e-9 of its scale only."""
    with pytest.warns(UnderResolvedWarning, match=r"max\|V\^n\|"):
        fe = analyse(*nodes(100), rate_check=False, max_N=101, kernel_resolve=None)
    assert fe.N == 101 and fe.resolved is False and not fe.success
    assert fe.polished.residual > 1e-9 * fe.polished.residual_scale


def test_refinement_limit_of_reproduce_folded(monkeypatch):
    """The command's largest grid is the one whose whole spectrum fits in the memory."""
    from qsa.commands._memory import FOOTPRINTS, MARGIN
    from qsa.commands.reproduce_folded import refinement_limit

    monkeypatch.setenv("QSA_MEMORY_LIMIT", "64G")
    assert refinement_limit() == 4801
    monkeypatch.setenv("QSA_MEMORY_LIMIT", "8G")
    N = refinement_limit()
    fp = FOOTPRINTS["spectrum-fourier"]
    assert 1201 < N < 4801
    assert MARGIN * fp.peak(N) <= 8 * 2**30 < MARGIN * fp.peak(N + 1)
