"""DAE flow against the front ODE; reduced against full slow eigenvalues; the CLI."""

import argparse
import json

import numpy as np
import pytest

from qsa.paper import SCENARIOS, Scenario, compare_eigenvalues, compare_fronts


def test_slow_eigenvalues_match_full_linearization():
    # equilateral triangle (polished to an exact equilibrium): a double slow pair
    r = compare_eigenvalues(3, facet=0.35, N=285)
    assert r.polish_success
    assert max(abs(r.rigid)) < 0.01 * min(r.full)  # kernel well separated
    assert r.max_rel_diff < 0.1
    assert min(r.full) > 0  # facets attract: splices are unstable
    assert r.summary()["n_corners"] == 3 and r.summary()["reduced"] == r.reduced.tolist()


@pytest.mark.slow
def test_slow_eigenvalues_square():
    r = compare_eigenvalues(Scenario.regular(4, 0.35), N=285)
    assert len(r.reduced) == 4 and r.max_rel_diff < 0.1


def test_short_facet_fast_variant():
    # coarse DAE (N = 400): collision time within 10%, early positions close
    c = compare_fronts("short-facet", N=400)
    s = c.summary()
    assert s["collision_dae"] == c.collision_dae and s["max_error"] == c.max_error
    assert np.isfinite(s["collision_dae"]) and np.isfinite(s["collision_ode"])
    assert s["collision_rel_diff"] < 0.1
    assert s["error_at"]["0.5"] < 0.05
    assert c.dae.shape[1] == 8 and np.all(np.isfinite(c.dae))
    v = s["variable_length"]
    assert v["collision_rel_diff"] < 0.1 and v["error_at"]["0.5"] < 0.05
    # the splice manifold's range (every DAE gap >= 2 d_c) is the same data for both
    assert v["separated_until"] == s["separated_until"] and 0.5 < v["separated_until"] < 1
    assert v["error_at"]["0.5"] <= v["max_error_separated"] <= v["max_error"]
    assert v["L_change"] < 0  # the collapsing facet shortens the curve, as in the DAE


def test_short_facet_newton_correction():
    # the corrected force (qsa.reduction.correction) with the length as an unknown:
    # collision time within 1% (uncorrected 2.4%), positions within 5% to 0.99 t_c
    s = compare_fronts("short-facet", N=600, correction="newton").summary()
    assert s["correction"] == "newton"
    v = s["variable_length"]
    assert v["collision_rel_diff"] < 0.01
    assert v["error_at"]["0.99"] < 0.05
    assert s["collision_rel_diff"] < 0.02  # fixed length: the perimeter mode remains


@pytest.mark.slow
@pytest.mark.parametrize("scenario", ["triangle", "short-facet"])
def test_dae_vs_ode_resolved(scenario):
    s = compare_fronts(scenario, N=1200).summary()
    assert s["collision_rel_diff"] < 0.1
    # within 5% of the smallest facet up to 0.95 t_c; beyond, the error grows like
    # eps / (1 - t/t_c) (see qsa.reduction.integrate, "Validity")
    assert s["error_at"]["0.95"] < 0.05
    v = s["variable_length"]
    assert v["collision_rel_diff"] < 0.1
    assert v["error_at"]["0.95"] < 0.05


def test_reproduce_fronts_cli(tmp_path, capsys):
    from qsa.commands import reproduce

    parser = argparse.ArgumentParser(prog="qsa")
    sub = parser.add_subparsers(dest="command")
    reproduce.add_parser(sub)
    png = tmp_path / "f.png"
    args = parser.parse_args(["reproduce", "fronts", "--scenario", "short-facet", "--N", "300",
                              "--json", "--plot", str(png), "--out", str(tmp_path / "o"),
                              "--dae-check", "200"])
    assert args.func(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["scenario"] == "short-facet" and out["N"] == 300
    # the DAE against itself at another resolution: close early, diverging at the collision
    d = out["dae_spread"]
    assert d["N"] == 200 and d["collision_rel_diff"] < 0.05
    assert d["error_at"]["0.5"] < 0.02 < d["max_error"]
    assert d["error_at"]["0.5"] <= d["error_at"]["0.9"] <= d["max_error"]
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "o" / "fronts_short-facet.json").exists()
    from qsa.cli import main

    capsys.readouterr()
    assert main(["reproduce", "fronts", "--N", "10"]) == 2  # refused by the option's type
    assert "argument --N: must be an integer >= 50, got 10" in capsys.readouterr().err


def test_no_collision_before_t_final():
    # the old keyword signature (alpha, kstar, beta next to the scenario) still works
    s = compare_fronts(SCENARIOS["short-facet"], N=300, t_final=0.01, alpha=0.1, kstar=5.0,
                       beta=5.0).summary()
    assert (s["alpha"], s["kstar"], s["beta"]) == (0.1, 5.0, 5.0)
    assert np.isnan(s["collision_dae"]) and np.isnan(s["collision_ode"])
    assert np.isfinite(s["max_error"]) and s["max_error"] < 0.05


def test_profile_manifold_reduction_against_the_dae():
    """The quasi-steady profiles with the length fixed and free (N = 1200: +1.9% and
    +1.0%, with the lag +1.2% and +0.3%)."""
    c = compare_fronts("short-facet", N=400, correction="profile")
    s = c.summary()
    assert s["correction"] == "profile" and c.collision_rel_diff < 0.03
    v = s["variable_length"]
    assert v["collision_rel_diff"] < 0.03 and v["L_change"] != 0.0
