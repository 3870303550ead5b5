"""``qsa reproduce spacing``: the near-contact spacing of a polished fold against d*."""

import json

import numpy as np

from qsa.cli import main


def test_reproduce_spacing_text_and_out(capsys, tmp_path):
    argv = ["reproduce", "spacing", "--l-star", "0.1", "0.2", "--start", "0.1", "--N", "201",
            "--t-flow", "0.3", "--nodes-per-l-star", "3", "--no-grid-check"]
    assert main([*argv, "--out", str(tmp_path)]) == 0
    text = capsys.readouterr()
    assert "| 0.2 |" in text.out and "fitted order" in text.out
    assert "polishing a zipped dumbbell" in text.err and "l* = 0.2: N =" in text.err
    out = json.loads((tmp_path / "spacing.json").read_text())
    assert out["figures"] == [str(tmp_path / "spacing.png")]
    assert (tmp_path / "spacing.png").stat().st_size > 1000
    assert out["success"] and [p["l_star"] for p in out["points"]] == [0.1, 0.2]
    for p in out["points"]:
        assert p["relative_residual"] <= 1e-9 and p["refined_spacing"] is None
        assert p["target"] == np.sqrt(1.5) * p["l_star"]
        assert abs(p["relative_error"]) < 1e-4
