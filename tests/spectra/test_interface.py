"""Bad input, result fields, plots and the ``qsa spectrum`` command."""

import argparse
import json

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Energy
from qsa.equilibria import circle
from qsa.spectra import (
    DENSE_CONSTRAINT_LIMIT,
    MESSAGES,
    KernelReport,
    Spectrum,
    hessian,
    kernel_report,
    lagrange_hessian,
    linearization,
    spectrum,
)
from tests.helpers import assert_status_convention


@pytest.fixture(scope="module")
def eq():
    return circle(0.7, 0.1, grid=Fourier(25))


def test_bad_input_raises_value_error_naming_the_argument(eq):
    E, c = eq.energy, eq.curve
    with pytest.raises(ValueError, match="energy"):
        spectrum(None, c)
    with pytest.raises(ValueError, match="curve"):
        spectrum(E, np.ones(25))
    with pytest.raises(ValueError, match="gauge"):
        spectrum(E, c, gauge="lab")
    with pytest.raises(ValueError, match="gauge"):
        linearization(E, c, gauge="Normal")
    with pytest.raises(ValueError, match="k must"):
        spectrum(E, c, k=0)
    with pytest.raises(ValueError, match="k=30"):
        spectrum(E, c, k=30)
    with pytest.raises(ValueError, match="sigma"):
        spectrum(E, c, k=3, sigma=np.nan)
    with pytest.raises(ValueError, match="kernel_tol"):
        spectrum(E, c, kernel_tol=-1.0)
    with pytest.raises(ValueError, match="factor"):
        spectrum(E, c, factor=10.0)
    with pytest.raises(ValueError, match="drift_tol"):
        spectrum(E, c, drift_tol=0.0)
    with pytest.raises(ValueError, match="constraints"):
        lagrange_hessian(E, c, constraints="some")
    with pytest.raises(ValueError, match="energy"):
        kernel_report("E", c)
    with pytest.raises(ValueError, match="energy"):
        hessian(object(), c)


def test_scaled_gauge_needs_constant_g(eq):
    c = eq.curve
    g = c.g * (1 + 0.1 * np.cos(2 * np.pi * c.grid.s))
    with pytest.raises(ValueError, match="constant g"):
        linearization(eq.energy, c.with_g(g), gauge="scaled")


class _PsiOne(Energy):
    """A test energy with nabla_I E = Psi_1 (so Lambda = (1, 0, 0)) and zero Hessian."""

    def energy(self, c):
        return 0.0

    def gradient(self, c):
        from qsa.geometry import constraint_gradients

        return constraint_gradients(c)[0]

    def hessian(self, c):
        import scipy.sparse as sp

        return sp.csr_matrix((2 * c.N, 2 * c.N))


def test_large_fd_curve_keeps_significant_constraint_terms_factored():
    from qsa.geometry import constraint_hessians
    from qsa.linalg import ReducedHessian
    from tests.helpers import skew_curve

    c = skew_curve(FiniteDifference(DENSE_CONSTRAINT_LIMIT + 100))
    E = _PsiOne()
    assert np.allclose(lagrange_hessian(E, skew_curve(FiniteDifference(200))).multipliers,
                       [1, 0, 0], atol=1e-10)
    LH = lagrange_hessian(E, c)
    assert LH.constraints_included == (True, True, True)
    assert isinstance(LH.matrix, ReducedHessian)
    V = np.random.default_rng(0).standard_normal((2 * c.N, 2))
    ref = -(constraint_hessians(c)[0] @ V)
    assert np.abs(LH.matrix @ V - ref).max() < 1e-10 * np.abs(ref).max()
    LH = lagrange_hessian(E, c, constraints="curvature")
    assert LH.constraints_included == (False, False, True)
    # on a dense grid the significant Lambda_1 term is included: L = 0 - 1 * H_C1
    cf = skew_curve(Fourier(31))
    LH = lagrange_hessian(E, cf)
    assert LH.constraints_included == (True, True, True)
    assert np.allclose(LH.matrix, -constraint_hessians(cf)[0], atol=1e-10)


def test_result_types_and_json_summary(eq):
    s = spectrum(eq.energy, eq.curve)
    assert isinstance(s, Spectrum) and isinstance(s.kernel, KernelReport)
    with pytest.raises(AttributeError):
        s.n_unstable = 0  # frozen
    d = json.loads(json.dumps(s.summary()))
    assert d["n_unstable"] == s.n_unstable and d["kernel"]["expected_kernel_dimension"] == 2
    assert np.all(s.unstable > 0) and s.unstable.size == s.n_unstable
    # eigenvalues sorted, most unstable first
    assert np.all(np.diff(s.eigenvalues) <= 0)


def test_failed_solve_is_reported_not_raised(eq, monkeypatch):
    import qsa.spectra.solvers as solvers

    def broken(*a, **k):
        raise np.linalg.LinAlgError("no convergence")

    monkeypatch.setattr(solvers.sla, "eigh", broken)
    s = spectrum(eq.energy, eq.curve)
    assert not s.success and s.status == -1 and "no convergence" in s.message
    assert s.eigenvalues.size == 0
    assert_status_convention(s, MESSAGES)


def test_plots(eq, tmp_path):
    from qsa import plotting

    s = spectrum(eq.energy, eq.curve)
    ax = plotting.plot_spectrum(s)
    assert len(ax.lines) >= 3
    fig = plotting.plot_eigenmode(s, eq.curve, index=0)
    plotting.save(fig, tmp_path / "m.png")
    assert (tmp_path / "m.png").read_bytes()[:4] == b"\x89PNG"
    phi, k1 = plotting.eigenmode_fields(s, eq.curve, 0)
    # circle: kappa1 = G phi = (k^2 - 1) phi / R^2 for the mode cos k theta
    assert np.allclose(k1, -(np.sum(k1 * phi) / np.sum(phi * phi)) * -phi, atol=1e-8)
    sc = spectrum(eq.energy, eq.curve, gauge="comoving")
    plotting.plot_eigenmode(sc, eq.curve, index=0)
    sp_ = spectrum(eq.energy, eq.curve, gauge="paper")
    plotting.plot_spectrum(sp_)
    with pytest.raises(ValueError, match="index"):
        plotting.plot_eigenmode(s, eq.curve, index=99)


def _run(argv):
    from qsa.commands import spectrum as cmd

    parser = argparse.ArgumentParser(prog="qsa")
    sub = parser.add_subparsers(dest="command")
    cmd.add_parser(sub)
    args = parser.parse_args(["spectrum", *argv])
    return args.func(args)


def test_cli_json_plot_and_text(tmp_path, capsys):
    png = tmp_path / "s.png"
    assert _run(["npulse", "--pulses", "3", "--alpha", "0.3", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["spectrum"]["n_kernel"] == 3 and out["spectrum"]["n_unstable"] == 3
    assert out["spectrum"]["kernel"]["kernel_dimension"] == 3
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert _run(["circle", "--radius", "0.7", "--alpha", "0.1", "--N", "25", "--gauge",
                 "comoving", "--plot", str(tmp_path / "m.png"), "--mode", "0"]) == 0
    text = capsys.readouterr().out
    assert "comoving gauge" in text and "figure written" in text
    assert _run(["circle", "--radius", "0.7", "--alpha", "0.1", "--N", "200", "--fd",
                 "--k", "6", "--sigma", "0"]) == 0
    assert "shift-invert (k=6" in capsys.readouterr().out


def test_cli_splice_warns_in_the_summary(capsys):
    assert _run(["splice", "--angles", "120", "120", "120", "--facets", "1", "1.3", "1",
                 "--alpha", "0.2", "--no-reject", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["warnings"] and "not an equilibrium" in out["warnings"][0]
    assert out["spectrum"]["relative_residual"] > 1e-6


def test_cli_main_registers_spectrum():
    from qsa.cli import build_parser

    args = build_parser().parse_args(["spectrum", "circle", "--radius", "1", "--alpha", "0.1"])
    assert args.gauge == "normal"


def test_energy_kernel_note_only_when_lambda3_matters():
    c = Curve.circle(1.0, Fourier(17))
    from qsa.energies import CanhamHelfrich, Perimeter

    k = kernel_report(CanhamHelfrich(1.0) + Perimeter(1.0, 2 * np.pi - 0.5), c)
    assert any("circle" in n for n in k.notes)
    assert k.lagrange_kernel == 0.0 and k.energy_kernel == 0.0


def test_lanczos_norm_is_a_lower_bound_exact_on_exhausting_the_space():
    from qsa.spectra.kernel import lanczos_norm

    rng = np.random.default_rng(4)
    n = 40
    w = rng.uniform(0.5, 2.0, n)
    A = rng.standard_normal((n, n))
    S = (A + A.T) / w[:, None]  # w-self-adjoint: W S symmetric
    rw = np.sqrt(w)
    normA = np.linalg.norm(rw[:, None] * A / rw[None, :], 2)
    normS = np.max(np.abs(np.linalg.eigvals(S).real))
    gk = [lanczos_norm(lambda x: A @ x, lambda x: A.T @ x, w, k) for k in (3, 10, n)]
    la = [lanczos_norm(lambda x: S @ x, None, w, k) for k in (3, 10, n)]
    assert gk[0] <= gk[1] + 1e-12 <= normA * (1 + 1e-12) and gk[2] == pytest.approx(normA, 1e-10)
    assert la[0] <= la[1] + 1e-12 <= normS * (1 + 1e-12) and la[2] == pytest.approx(normS, 1e-10)
    # a non-finite product ends the iteration with the estimate so far (0 on the first)
    assert lanczos_norm(lambda x: x * np.nan, None, w, 5) == 0.0


def test_operator_norm_and_second_resolution(eq):
    from qsa.spectra import normal_operator, operator_norm, second_resolution

    J = normal_operator(eq.energy, eq.curve)
    lam = np.linalg.eigvals(J).real
    # J is dsigma-self-adjoint: its <.,.>-norm is its spectral radius
    assert operator_norm(eq.curve, J, iters=200) == pytest.approx(np.max(np.abs(lam)), rel=1e-6)
    assert operator_norm(eq.curve, J, iters=200, symmetric=True) == pytest.approx(
        np.max(np.abs(lam)), rel=1e-6)
    assert second_resolution(Fourier(81)) == Fourier(123)
    assert second_resolution(FiniteDifference(100)) == FiniteDifference(150)
