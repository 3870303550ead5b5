"""``qsa equilibrium ...``: JSON summary, plot file, exit codes, bad input."""

import argparse
import json

import pytest

from qsa.commands import equilibrium


def run(argv):
    parser = argparse.ArgumentParser(prog="qsa")
    sub = parser.add_subparsers(dest="command")
    equilibrium.add_parser(sub)
    args = parser.parse_args(["equilibrium", *argv])
    return args.func(args)


def test_npulse_json_and_plot(tmp_path, capsys):
    png = tmp_path / "np.png"
    assert run(["npulse", "--pulses", "3", "--alpha", "0.2", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "npulse" and out["success"]
    assert out["params"]["n_pulses"] == 3 and out["closure"] < 1e-10
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_splice_and_circle_text(capsys):
    assert run(["splice", "--angles", "120", "120", "120", "--facets", "1", "1", "1",
                "--alpha", "0.1"]) == 0
    assert "splice: closure" in capsys.readouterr().out
    assert run(["circle", "--radius", "0.7", "--alpha", "0.1", "--N", "33"]) == 0
    assert "L_star" in capsys.readouterr().out


def test_bad_request_raises_value_error():
    with pytest.raises(ValueError, match="N alpha < 1"):
        run(["npulse", "--pulses", "4", "--alpha", "0.3"])
    with pytest.raises(ValueError, match="same number"):
        run(["splice", "--angles", "180", "180", "--facets", "1", "--alpha", "0.1"])
