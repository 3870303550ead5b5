import json

import pytest

from qsa import __version__
from qsa.cli import main


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_help_lists_subcommands(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert "demo" in out and "equilibrium" in out


def test_demo_writes_summary_and_figures(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert on_disk["curves"]["trillium"]["N"] == summary["curves"]["trillium"]["N"]
    t = summary["curves"]["trillium"]
    assert t["closure"] < 1e-10
    assert t["max_M_rigid"] < 1e-8 and t["max_Mdagger_Psi"] < 1e-8
    for name in ("faceting", "canham_helfrich"):
        assert t[name]["gradient_rel_error"] < 1e-6
        assert t[name]["hessian_rel_error"] < 1e-5
        assert t[name]["dissipation_rate"] < 0
    assert summary["curves"]["circle"]["closure"] < 1e-12
    n = summary["npulse"]
    assert n["success"] and n["closure"] < 1e-10 and n["residual"] < 1e-8 * n["residual_scale"]
    s = summary["spectrum"]
    assert s["success"] and s["n_kernel"] == s["kernel"]["expected_kernel_dimension"] == 3
    assert s["kernel"]["lagrange_kernel"] < 1e-6 and s["max_imag"] < 1e-8
    sp = summary["splice"]
    assert sp["closure"] < 1e-12 and sp["n_small"] == sp["n_small_expected"] == 5
    # the facets reported (and in the figure's title) are those of the curve: the closing
    # facets for these angles, close to the requested 0.9, 1.0, 1.1 but not equal
    assert sp["facets_requested"] == [0.9, 1.0, 1.1] and sp["facets"] != [0.9, 1.0, 1.1]
    assert sp["facets"] == pytest.approx([0.9, 1.0, 1.1], abs=5e-3)
    assert sp["separation"] > 100
    f = summary["flow"]
    assert f["success"] and f["relative_error"] < 0.02  # DAE decay rate = eigenvalue of J
    assert f["max_energy_increase"] <= 1e-10 * abs(summary["npulse"]["energy"])
    for fname in summary["figures"]:
        assert (tmp_path / fname).stat().st_size > 10_000


def test_bad_input_is_one_clear_line(capsys):
    assert main(["equilibrium", "npulse", "--pulses", "1", "--alpha", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "error" in err and "Traceback" not in err
