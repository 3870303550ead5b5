"""Result files round-trip: save -> qsa.io.load -> the same fields, for every file kind."""

import dataclasses
import json
import os

import numpy as np
import pytest

from qsa.cli import main
from qsa.equilibria import circle, npulse, polish, splice_polygon
from qsa.flows import CHA, FacetingFlow, FlowResult, solve_flow
from qsa.io import (
    load,
    load_equilibrium,
    load_npz,
    save_equilibrium,
    save_flow_result,
    save_npz,
    save_spectrum,
)
from qsa.spectra import spectrum


def assert_same_value(a, b, name):
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)
    elif isinstance(a, float) and np.isnan(a):
        assert np.isnan(b), name
    else:
        assert a == b and type(a) is type(b) or (a == b and np.isscalar(a)), (name, a, b)


def assert_same_curve(a, b):
    assert a.grid == b.grid and a.theta0 == b.theta0 and a.origin == b.origin
    np.testing.assert_array_equal(a.kappa, b.kappa)
    np.testing.assert_array_equal(a.g, b.g)


def assert_same_equilibrium(a, b):
    assert_same_curve(a.curve, b.curve)
    assert a.energy.params() == b.energy.params()
    assert a.energy.energy(a.curve) == b.energy.energy(b.curve)
    assert a.params == b.params
    for f in ("multipliers", "residual", "closure", "residual_scale", "kind", "success",
              "message"):
        assert_same_value(getattr(a, f), getattr(b, f), f)


@pytest.mark.parametrize("make", [
    lambda: npulse(3, 0.2, grid=141),
    lambda: splice_polygon(np.radians([90, 135, 135]), [1, 1.4, 1], 0.15, kstar=5.0,
                           grid=__import__("qsa").FiniteDifference(400)),
    lambda: circle(0.7, 0.1, grid=33, kstar=5.0),
])
def test_equilibrium_round_trip(make, tmp_path):
    eq = make()
    path = save_equilibrium(tmp_path / "eq.npz", eq)
    back = load(path)
    assert type(back).__name__ == "Equilibrium"
    assert_same_equilibrium(eq, back)
    assert load_npz(path)[1]["kind"] == "qsa.equilibrium"


def test_polished_equilibrium_round_trip(tmp_path):
    eq = npulse(3, 0.2, grid=141)
    eq = polish(eq.energy, eq.curve, tol=1e-10)
    assert_same_equilibrium(eq, load(save_equilibrium(tmp_path / "p.npz", eq)))


def test_spectrum_round_trip_keeps_every_field(tmp_path):
    eq = npulse(3, 0.2, grid=141)
    spec = spectrum(eq.energy, eq.curve)
    path = save_spectrum(tmp_path / "sp.npz", spec, eq)
    back = load(path)
    assert type(back).__name__ == "Spectrum"
    for f in dataclasses.fields(spec):
        if f.name == "kernel":
            for g in dataclasses.fields(spec.kernel):
                assert_same_value(getattr(spec.kernel, g.name), getattr(back.kernel, g.name),
                                  f"kernel.{g.name}")
        else:
            assert_same_value(getattr(spec, f.name), getattr(back, f.name), f.name)
    assert_same_equilibrium(eq, load_equilibrium(path))
    assert back.summary(5) == spec.summary(5)


def test_complex_spectrum_round_trip(tmp_path):
    eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    spec = spectrum(eq.energy, eq.curve, gauge="paper")
    back = load(save_spectrum(tmp_path / "c.npz", spec, eq))
    assert np.iscomplexobj(spec.eigenvalues) and back.eigenvalues.dtype == np.complex128
    np.testing.assert_array_equal(back.eigenvalues, spec.eigenvalues)
    np.testing.assert_array_equal(back.eigenvectors, spec.eigenvectors)


def _flow(tmp_path, **kw):
    th = 2 * np.pi * np.arange(200) / 200
    r = 1 + 0.2 * np.cos(3 * th)
    return solve_flow(CHA(eps=0.1, beta=1.0, rho=1.2), (r * np.cos(th), r * np.sin(th)), 0.004,
                      N=40, tol=1e-3, t_eval=np.linspace(0, 0.004, 4),
                      checkpoint=tmp_path / "ck.npz", **kw)


def assert_same_flow(a, b, skip=()):
    for f in dataclasses.fields(FlowResult):
        if f.name not in ("system",) + tuple(skip):
            assert_same_value(getattr(a, f.name), getattr(b, f.name), f.name)
    assert a.system.metadata() == b.system.metadata()
    assert a.system.energy(a.states[-1]) == pytest.approx(b.system.energy(b.states[-1]),
                                                           rel=1e-13)


def test_flow_result_and_checkpoint_round_trip(tmp_path):
    res = _flow(tmp_path)
    back = load(save_flow_result(tmp_path / "result.npz", res))
    assert isinstance(back, FlowResult)
    assert_same_flow(res, back)
    from_checkpoint = load(tmp_path / "ck.npz")
    assert isinstance(from_checkpoint, FlowResult)
    assert from_checkpoint.status == 0 and from_checkpoint.success
    assert_same_flow(res, from_checkpoint, skip=("message", "checkpoint"))


def test_faceting_flow_result_round_trip(tmp_path):
    th = 2 * np.pi * np.arange(300) / 300
    r = 1 + 0.05 * np.cos(5 * th)
    res = solve_flow(FacetingFlow(0.3, 2.0, 5.0, 7.0), (r * np.cos(th), r * np.sin(th)), 2e-4,
                     N=48, tol=1e-3)
    assert_same_flow(res, load(save_flow_result(tmp_path / "f.npz", res)))


def test_second_order_and_constrained_flow_results_round_trip(tmp_path):
    from qsa.constraints import FixedArea
    from qsa.energies import Faceting, Perimeter
    from qsa.flows import SecondOrderFlow

    th = 2 * np.pi * np.arange(300) / 300
    r = 1 + 0.05 * np.cos(5 * th)
    xy = (r * np.cos(th), r * np.sin(th))
    res = solve_flow(SecondOrderFlow(Faceting(0.3, 2.0) + Perimeter(5.0, 7.0)), xy, 2e-4,
                     N=48, tol=1e-3)
    assert_same_flow(res, load(save_flow_result(tmp_path / "s.npz", res)))
    res = solve_flow(FacetingFlow(0.3, 2.0, 5.0, 7.0), xy, 2e-4, N=48, tol=1e-3,
                     constraints=[FixedArea()])
    back = load(save_flow_result(tmp_path / "a.npz", res))
    assert_same_flow(res, back)
    assert back.system.bound_constants() == res.system.bound_constants()


def test_files_get_the_umask_and_replaced_files_keep_their_mode(tmp_path):
    old = os.umask(0o022)
    try:
        save_npz(tmp_path / "a.npz", {"y": np.zeros(2)}, {})
        assert (tmp_path / "a.npz").stat().st_mode & 0o777 == 0o644
        os.umask(0o077)
        save_npz(tmp_path / "b.npz", {"y": np.zeros(2)}, {})
        assert (tmp_path / "b.npz").stat().st_mode & 0o777 == 0o600
        os.chmod(tmp_path / "a.npz", 0o640)
        save_npz(tmp_path / "a.npz", {"y": np.ones(2)}, {})  # replaced atomically
        assert (tmp_path / "a.npz").stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(old)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz", "b.npz"]


def test_load_refuses_files_without_a_result_object(tmp_path):
    save_npz(tmp_path / "run.npz", {"t": np.zeros(3)}, {"kind": "qsa.run-series"})
    with pytest.raises(ValueError, match="no result object.*load_npz"):
        load(tmp_path / "run.npz")
    save_npz(tmp_path / "old.npz", {"t": np.zeros(3)}, {"n_steps": 3})
    with pytest.raises(ValueError, match="no 'kind'"):
        load(tmp_path / "old.npz")


def test_an_energy_its_parameters_do_not_describe_is_refused(tmp_path):
    from dataclasses import replace

    from qsa.energies import EnergySum, Faceting, Perimeter, Well

    eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    well = Well(W=lambda k: k**2 * (k - 5.0) ** 2 / 2, dW=lambda k: k * (k - 5.0) * (2 * k - 5.0),
                d2W=lambda k: 6 * k**2 - 30 * k + 25.0, kstar=5.0)
    energy = EnergySum((Faceting(0.1, 5.0, well=well), Perimeter(5.0, eq.params["L_star"])))
    with pytest.raises(ValueError, match="cannot be stored"):
        save_equilibrium(tmp_path / "x.npz", replace(eq, energy=energy))
    assert not (tmp_path / "x.npz").exists()


# -------------------------------------------------------------- command line
def test_command_line_save_and_flow_from_a_saved_equilibrium(tmp_path, capsys):
    eq_path, sp_path = tmp_path / "eq.npz", tmp_path / "sp.npz"
    assert main(["equilibrium", "npulse", "--pulses", "3", "--alpha", "0.2", "--polish",
                 "--save", str(eq_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    eq = load(eq_path)
    assert summary["file"] == str(eq_path) and eq.kind == "polished"
    assert eq.residual == summary["residual"] and eq.params["n_pulses"] == 3
    assert main(["spectrum", "npulse", "--pulses", "3", "--alpha", "0.2", "--save",
                 str(sp_path), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)["spectrum"]
    spec = load(sp_path)
    assert spec.n_unstable == s["n_unstable"] and spec.eigenvalues[:5].tolist() == \
        pytest.approx(s["eigenvalues"][:5], rel=0, abs=0)
    # the faceting flow from the saved equilibrium (its alpha, kappa*, beta, L*) barely moves
    assert main(["flow", "facet", "--init", str(eq_path), "--N", "200", "--t-final", "1e-4",
                 "--json", "--no-progress"]) == 0
    f = json.loads(capsys.readouterr().out)
    assert f["model"]["alpha"] == 0.2 and f["model"]["L_star"] == eq.params["L_star"]
    assert abs(f["energy_final"] - f["energy_initial"]) < 1e-4 * f["energy_initial"]
    assert main(["flow", "facet", "--init", str(sp_path), "--N", "200", "--t-final", "1e-4",
                 "--json", "--no-progress"]) == 0
    assert json.loads(capsys.readouterr().out)["model"]["L_star"] == eq.params["L_star"]
