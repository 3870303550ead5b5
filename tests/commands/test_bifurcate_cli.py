"""``qsa bifurcate ...``: JSON summary, files (CSV, JSON, npz), plot, exit codes, bad input."""

import csv
import json

import numpy as np
import pytest

from qsa.cli import main
from qsa.io import load_npz

ARGS = ["bifurcate", "circle", "--radius", "0.95", "--alpha", "0.1", "--N", "33",
        "--stop", "5.45"]


def test_json_files_and_plot_with_switching(tmp_path, capsys):
    png = tmp_path / "d.png"
    out_dir = tmp_path / "branches"
    code = main(ARGS + ["--switch", "0", "--max-steps", "30", "--json", "--plot", str(png),
                        "--out", str(out_dir)])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    main_branch, switched = out["branches"]
    assert [b["sector"] for b in main_branch["bifurcations"]][:1] == [2]
    assert all(b["multiplicity"] == 2 and b["label"] == "mode"
               for b in main_branch["bifurcations"])
    assert "switched at L_star" in switched["message"]
    assert png.read_bytes()[:4] == b"\x89PNG"
    rows = list(csv.DictReader(open(out_dir / "branch0.csv")))
    assert len(rows) == len(main_branch["values"])
    assert [float(r["parameter"]) for r in rows] == main_branch["values"]
    arrays, meta = load_npz(out_dir / "branch1.npz")
    assert arrays["kappa"].shape == (len(switched["values"]), 33)
    assert np.ptp(arrays["kappa"][-1]) > 0 and meta["kind"] == "branch"
    assert json.load(open(out_dir / "branch0.json"))["status"] == 0


def test_text_output_lists_the_bifurcations(capsys):
    assert main(ARGS) == 0
    text = capsys.readouterr().out
    assert "[0] branch L_star = 5.514412" in text and "mode 2" in text


@pytest.mark.parametrize("extra, match", [(["--switch", "7"], "there are 2 bifurcations"),
                                          (["--switch", "x"], "indices"),
                                          (["--stop", "0.0", "--radius", "-1"], "radius")])
def test_bad_input_is_one_line_and_exit_2(extra, match, capsys):
    assert main(ARGS + extra) == 2
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1


def test_the_pressurized_ring(capsys):
    code = main(["bifurcate", "ring", "--N", "33", "--stop", "-9", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    (ring,) = out["branches"]
    bifs = ring["bifurcations"]
    assert [b["sector"] for b in bifs] == [2, 3]
    assert [b["parameter"] for b in bifs] == pytest.approx([-3.0, -8.0], rel=1e-8)
    assert out["equilibrium"] is None
    assert main(["bifurcate", "ring", "--eps", "-1", "--stop", "-9"]) == 2
