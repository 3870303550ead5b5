"""``qsa equilibrium cha`` and ``qsa spectrum cha``: a folded CHA state read from a file.

The state is the appendix CHA equilibrium (l* = 0.5) sampled at 160 nodes with a
small bump, as a flow's last nodes would be (tests/paper/test_folded.py), written as
a ``qsa reproduce`` run's ``<name>.npz``, as a ``qsa flow cha --out`` result and
checkpoint, and as the ``--save`` of the commands themselves.
"""

import json

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.cli import main
from qsa.equilibria import Equilibrium, circle
from qsa.io import load, load_equilibrium, save_equilibrium
from qsa.paper._files import write_output
from qsa.paper.folded import folded_energy, folded_equilibrium
from tests.helpers import CHA_REF as REF
from tests.helpers import folded_nodes as nodes

RHO = 1.5
PARAMS = {"eps": REF["eps"], "beta": REF["beta"], "rho": RHO, "A0": REF["A0"],
          "l_star": REF["l_star"], "a": REF["a"]}
L0 = REF["L_star"] / RHO


def run(capsys, *argv):
    """``(exit code, stdout, stderr)`` of ``qsa argv`` run in-process."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv):
    code, out, err = run(capsys, *argv, "--json")
    return code, json.loads(out), err


def one_error_line(err, *words):
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A paper run's ``<name>.npz``, a flow's result and checkpoint, and a saved state."""
    d = tmp_path_factory.mktemp("cha")
    x, y = nodes(noise=2e-3)
    write_output(str(d / "run"), "cha_rho1.5",
                 {"snap_t": np.array([0.0, 1.0]), "snap_x": np.array([x, x]),
                  "snap_y": np.array([y, y])},
                 {"scenario": "cha_rho1.5", "params": {**PARAMS, "N": x.size}, "L0": L0})
    np.savetxt(d / "nodes.txt", np.column_stack([x, y]))
    L = float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))
    assert main(["flow", "cha", "--init", str(d / "nodes.txt"), "--N", "160",
                 "--t-final", "1e-5", "--rho", repr(REF["L_star"] / L), "--snapshots", "2",
                 "--no-progress", "--no-plots", "--out", str(d / "flow")]) == 0
    assert main(["equilibrium", "cha", "--from", str(d / "run" / "cha_rho1.5.npz"),
                 "--polish", "--save", str(d / "eq.npz"), "--json"]) == 0
    return {"run": d / "run" / "cha_rho1.5.npz", "result": d / "flow" / "result.npz",
            "checkpoint": d / "flow" / "checkpoint.npz", "eq": d / "eq.npz",
            "nodes": (x, y), "dir": d}


def library(x, y=None, **options):
    """:func:`folded_equilibrium` with the parameters of the files, no spectrum by default."""
    options = {"rate_check": False, "with_spectrum": False, **options}
    p = {**PARAMS, "L0": L0, **options.pop("params", {})}
    return folded_equilibrium(x, y, **p, **options)


# ------------------------------------------------------------------ equilibrium
def test_polished_paper_run_matches_the_library(files, capsys):
    code, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files["run"], "--polish")
    assert code == 0 and s["success"] and s["polished"] and s["polish_success"]
    fe = library(*files["nodes"])
    ref = fe.summary()
    assert s["N"] == ref["N"] == 161 and s["n_newton"] == ref["n_newton"] > 0
    assert s["relative_residual"] <= 1e-10
    for key in ("energy", "length", "closure", "relative_residual"):
        assert s[key] == pytest.approx(ref[key], rel=1e-9, abs=1e-13), key
    assert s["params"] == pytest.approx(fe.params, rel=1e-15)
    assert s["name"] == "cha_rho1.5" and "reproduce run" in s["source"]


def test_without_polish_the_state_is_evaluated_as_read(files, capsys):
    code, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files["run"])
    assert code == 0 and not s["polished"] and s["n_newton"] == 0
    ref = library(*files["nodes"], maxiter=0)
    assert s["energy"] == pytest.approx(ref.energy.energy(ref.guess), rel=1e-12)
    assert s["relative_residual"] == pytest.approx(ref.relative_residual, rel=1e-12)
    assert s["relative_residual"] > 1e-3 and not s["polish_success"]
    code, out, _ = run(capsys, "equilibrium", "cha", "--from", files["run"])
    assert "the state as read" in out and "relative_residual" in out and "n_newton" in out


@pytest.mark.parametrize("which", ["result", "checkpoint"])
def test_flow_result_and_checkpoint(files, which, capsys):
    code, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files[which], "--polish")
    assert code == 0 and s["success"] and f"CHA flow {which}" in s["source"]
    res = load(files[which])
    meta = res.system.metadata()
    fe = library(res.x, res.y, params={k: meta[k] for k in (*PARAMS, "L0")})
    assert s["params"]["rho"] == pytest.approx(meta["rho"], rel=1e-15)
    assert s["params"]["L_star"] == pytest.approx(meta["rho"] * meta["L0"], rel=1e-15)
    assert s["params"]["L_star"] == pytest.approx(REF["L_star"], rel=1e-5)
    assert s["energy"] == pytest.approx(float(fe.energy.energy(fe.curve)), rel=1e-10)


def test_save_round_trip(files, capsys):
    eq = load(files["eq"])
    assert isinstance(eq, Equilibrium) and eq.kind == "polished" and eq.success
    assert [t["energy"] for t in eq.energy.params()["terms"]] == ["CanhamHelfrich",
                                                                   "Perimeter", "Adhesion"]
    assert eq.params["rho"] == RHO and eq.params["L0"] == pytest.approx(L0, rel=1e-15)
    code, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files["eq"])
    assert code == 0 and s["N"] == eq.curve.N and "equilibrium file" in s["source"]
    # read back as it was saved: no resampling of the polished curve
    assert s["relative_residual"] == pytest.approx(eq.relative_residual, rel=1e-6)
    assert s["relative_residual"] <= 1e-10
    assert s["energy"] == pytest.approx(float(eq.energy.energy(eq.curve)), rel=1e-14)
    # saved again without --polish: kind "cha", and still accepted
    code, _, _ = run(capsys, "equilibrium", "cha", "--from", files["eq"], "--save",
                     files["dir"] / "again.npz")
    assert code == 0 and load(files["dir"] / "again.npz").kind == "cha"
    # --N resamples the saved curve spectrally
    code, s2, _ = run_json(capsys, "equilibrium", "cha", "--from", files["eq"], "--N", "200")
    assert code == 0 and s2["N"] == 201
    assert s2["energy"] == pytest.approx(s["energy"], rel=1e-9)


def test_overrides_change_the_energy(files, capsys):
    _, base, _ = run_json(capsys, "equilibrium", "cha", "--from", files["eq"])
    eq = load(files["eq"])
    L = float(eq.curve.length())
    _, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files["eq"], "--rho", "1.6")
    assert s["params"]["rho"] == 1.6 and s["params"]["L_star"] == pytest.approx(1.6 * L0)
    # only the perimeter term beta/2 (L - rho L0)^2 changes
    shift = REF["beta"] / 2 * ((L - 1.6 * L0) ** 2 - (L - RHO * L0) ** 2)
    assert s["energy"] - base["energy"] == pytest.approx(shift, rel=1e-9)
    _, s, _ = run_json(capsys, "equilibrium", "cha", "--from", files["eq"], "--A0", "20",
                       "--eps", "0.2", "--l-star", "0.4", "--a", "1.1", "--beta", "2")
    p = {**PARAMS, "A0": 20.0, "eps": 0.2, "l_star": 0.4, "a": 1.1, "beta": 2.0}
    E = folded_energy(p["eps"], p["beta"], RHO * L0, p["A0"], p["l_star"], p["a"])
    assert s["params"] == pytest.approx({**p, "L0": L0, "L_star": RHO * L0}, rel=1e-15)
    assert s["energy"] == pytest.approx(float(E.energy(eq.curve)), rel=1e-12)
    assert abs(s["energy"] - base["energy"]) > 1.0


def test_plot_and_text(files, capsys):
    png = files["dir"] / "cha.png"
    code, out, _ = run(capsys, "equilibrium", "cha", "--from", files["eq"], "--plot", png)
    assert code == 0 and png.read_bytes()[:4] == b"\x89PNG"
    for word in ("N = 161", "energy", "closure", "rho = 1.5", "figure written"):
        assert word in out, word


# --------------------------------------------------------------------- spectrum
def test_spectrum_matches_the_library(files, capsys):
    png, sp_file = files["dir"] / "modes.png", files["dir"] / "sp.npz"
    code, s, _ = run_json(capsys, "spectrum", "cha", "--from", files["eq"], "--show", "4",
                          "--plot", png, "--save", sp_file)
    assert code == 0 and s["success"] and not s["warnings"]
    fe = library(load(files["eq"]).curve, n_slow=4, with_spectrum=True)
    ref = fe.summary()
    assert s["n_kernel"] == ref["n_kernel"] == 3
    assert s["n_unstable"] == ref["n_unstable"] and s["stable"] == ref["stable"]
    assert np.allclose(s["slowest_eigenvalues"], ref["slowest_eigenvalues"], rtol=1e-8)
    assert len(s["slowest_eigenvalues"]) == len(s["slowest_errors"]) == 4
    errors = fe.spectrum.errors[fe.slowest]
    assert np.allclose(s["slowest_errors"], errors, rtol=1e-3, atol=1e-12)
    assert png.read_bytes()[:4] == b"\x89PNG"
    # the spectrum file reads back, and its equilibrium is a state --from accepts
    back = load(sp_file)
    assert back.n_kernel == 3 and np.allclose(back.eigenvalues[fe.slowest],
                                              ref["slowest_eigenvalues"], rtol=1e-8)
    assert load_equilibrium(sp_file).params["rho"] == RHO
    code, s2, _ = run_json(capsys, "equilibrium", "cha", "--from", sp_file)
    assert code == 0 and s2["energy"] == pytest.approx(s["energy"], rel=1e-14)
    code, out, _ = run(capsys, "spectrum", "cha", "--from", sp_file, "--show", "2")
    assert code == 0
    assert "kernel 3 (|lambda| <= " in out and f"unstable {ref['n_unstable']}: " in out
    assert f"{ref['slowest_eigenvalues'][0]:.8g}"[:8] in out


# ----------------------------------------------------------------------- errors
def test_missing_file(files, capsys):
    code, _, err = run(capsys, "equilibrium", "cha", "--from", files["dir"] / "nope.npz")
    assert code == 2
    one_error_line(err, "--from", "nope.npz", "no such file")


def test_not_a_cha_state(files, capsys):
    facet = files["dir"] / "facet.npz"
    save_equilibrium(facet, circle(1.0, 0.1, grid=17))
    for command in ("equilibrium", "spectrum"):
        code, _, err = run(capsys, command, "cha", "--from", facet)
        assert code == 2
        one_error_line(err, "--from", "Faceting + Perimeter", "not a CHA state")
    code, _, err = run(capsys, "equilibrium", "cha", "--from", files["dir"] / "nodes.txt")
    assert code == 2
    one_error_line(err, "--from", "no qsa .npz", "not a CHA state")
    x, y = files["nodes"]
    write_output(str(files["dir"]), "facet", {"snap_t": np.array([0.0]), "snap_x": x[None],
                                              "snap_y": y[None]},
                 {"scenario": "facet", "params": {"alpha": 0.1, "kstar": 5.0, "beta": 5.0}})
    code, _, err = run(capsys, "equilibrium", "cha", "--from", files["dir"] / "facet.npz")
    assert code == 2
    one_error_line(err, "--from", "run 'facet'", "no CHA parameters", "not a CHA state")
    assert main(["flow", "facet", "--N", "40", "--t-final", "1e-7", "--no-progress",
                 "--no-plots", "--out", str(files["dir"] / "facet-flow")]) == 0
    capsys.readouterr()
    code, _, err = run(capsys, "spectrum", "cha", "--from",
                       files["dir"] / "facet-flow" / "result.npz")
    assert code == 2
    one_error_line(err, "--from", "FacetingFlow flow result", "not a CHA state")


def test_self_intersecting_states(files, capsys):
    t = 2 * np.pi * np.arange(200) / 200
    r = 0.5 + np.cos(t)                      # a limacon: an inner loop
    write_output(str(files["dir"]), "loop", {"snap_t": np.array([0.0]),
                                             "snap_x": (r * np.cos(t))[None],
                                             "snap_y": (r * np.sin(t))[None]},
                 {"scenario": "loop", "params": PARAMS, "L0": 5.0})
    code, _, err = run(capsys, "equilibrium", "cha", "--from", files["dir"] / "loop.npz")
    assert code == 2
    one_error_line(err, "--from", "intersect themselves", "segments")
    # a saved curve run round twice: polish and spectrum name the closest pair
    twice = Curve(np.full(129, 1.0), 4 * np.pi, Fourier(129))
    E = folded_energy(**{k: PARAMS[k] for k in ("eps", "beta", "A0", "l_star", "a")},
                      L_star=4 * np.pi)
    path = files["dir"] / "twice.npz"
    save_equilibrium(path, Equilibrium(twice, E, {"rho": 1.0}, np.zeros(3), 0.0, 0.0, 1.0))
    for command in ("equilibrium", "spectrum"):
        code, _, err = run(capsys, command, "cha", "--from", path, "--polish")
        assert code == 2
        one_error_line(err, "--from", "crosses itself", "segments", "s = ")


def test_failed_polish_exits_1_with_the_residual(files, capsys):
    for command in ("equilibrium", "spectrum"):
        code, out, err = run(capsys, command, "cha", "--from", files["run"], "--polish",
                             "--maxiter", "1")
        assert code == 1
        assert "maximum number of Newton iterations" in out and "max|V^n| = " in out
        one_error_line(err, "the polish failed")
    code, s, _ = run_json(capsys, "spectrum", "cha", "--from", files["run"], "--polish",
                          "--maxiter", "1")
    assert code == 1 and not s["success"] and "n_unstable" not in s
    assert s["relative_residual"] > 1e-6 and s["n_newton"] == 1


def test_cha_is_not_a_kind_of_bifurcate(capsys):
    code, _, err = run(capsys, "bifurcate", "cha", "--from", "x.npz")
    assert code == 2 and "invalid choice" in err


def test_spectrum_of_an_under_resolved_state_says_so(tmp_path, capsys):
    """A zipped dumbbell at 1.4 nodes per l*: polished (V^n ~ 1e-11 of its scale), but its
    rigid motions' eigenvalues are a large fraction of the slowest one, so the slow
    eigenvalues are not to be trusted: a warning, ``resolved`` False, exit status 1."""
    from qsa.paper.near_contact import paired_dumbbell

    st = paired_dumbbell(0.05, N=201, t_flow=0.5)
    x, y = st.curve.positions()
    p = st.params
    write_output(str(tmp_path), "cha_zip",
                 {"snap_t": np.array([0.0]), "snap_x": x[None], "snap_y": y[None]},
                 {"scenario": "cha_zip", "params": {**{k: p[k] for k in
                                                      ("eps", "beta", "rho", "A0", "l_star",
                                                       "a")}, "N": x.size},
                  "L0": p["L0"]})
    run_file = tmp_path / "cha_zip.npz"
    code, s, _ = run_json(capsys, "spectrum", "cha", "--from", run_file, "--show", "4")
    assert code == 1 and s["resolved"] is False and not s["success"]
    assert s["kernel_ratio"] > 1e-3
    assert any("does not resolve the state" in w for w in s["warnings"])
    code, out, _ = run(capsys, "spectrum", "cha", "--from", run_file, "--show", "4")
    assert code == 1 and "warning: the rigid motions' eigenvalues are" in out
