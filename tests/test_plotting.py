"""Figures people read: spectrum panels, tick labels, front counts, eigenmode labels, movies."""

import json

import numpy as np
import pytest
from PIL import Image

from qsa import plotting
from qsa.cli import main
from qsa.equilibria import circle, npulse
from qsa.flows import FacetingFlow, solve_flow
from qsa.spectra import spectrum


@pytest.fixture(scope="module")
def triangle_spectrum():
    eq = npulse(3, 0.1, kstar=5.0, beta=5.0)
    return eq, spectrum(eq.energy, eq.curve)


def tick_gaps(ax, axis="y"):
    """Distances in pixels between neighbouring major tick labels (drawn figure)."""
    ax.figure.canvas.draw()
    ticks = [t for t in getattr(ax, f"{axis}axis").get_major_ticks() if t.label1.get_text()]
    boxes = [t.label1.get_window_extent() for t in ticks]
    pos = np.sort([b.y0 if axis == "y" else b.x0 for b in boxes])
    size = max(b.height if axis == "y" else b.width for b in boxes)
    return np.diff(pos), size


def overlapping_tick_labels(fig):
    """``(panel, axis, label, label)`` for every two tick labels whose boxes overlap."""
    fig.canvas.draw()
    clashes = []
    for i, ax in enumerate(fig.axes):
        for name in ("x", "y"):
            labels = [t for t in getattr(ax, f"get_{name}ticklabels")() if t.get_text()]
            boxes = [t.get_window_extent() for t in labels]
            clashes += [(i, name, labels[a].get_text(), labels[b].get_text())
                        for a in range(len(boxes)) for b in range(a + 1, len(boxes))
                        if boxes[a].overlaps(boxes[b])]
    return clashes


def test_spectrum_near_zero_panel_and_readable_ticks(triangle_spectrum):
    eq, s = triangle_spectrum
    ax = plotting.plot_spectrum(s)
    main_ax, zoom = ax.figure.axes
    assert main_ax is ax
    # the near-zero panel: the 3 kernel modes and the 2 unstable coarsening modes
    near = plotting.near_zero_indices(s)
    assert near.tolist() == sorted(np.argsort(np.abs(s.eigenvalues))[:5].tolist())
    assert zoom.get_yscale() == "linear" and zoom.get_ylabel()
    lo, hi = zoom.get_ylim()
    assert lo < 0 < s.unstable.max() < hi < 2 * s.unstable.max()  # the unstable pair is legible
    # overview: symmetric-log, no two tick labels on top of each other
    assert main_ax.get_yscale() == "symlog"
    gaps, size = tick_gaps(main_ax)
    assert gaps.min() > 1.2 * size
    labels = [t.get_text() for t in main_ax.get_yticklabels() if t.get_text()]
    assert "0" in labels and len(set(labels)) == len(labels)
    assert overlapping_tick_labels(ax.figure) == []  # every axis of both panels


def test_spectrum_into_given_axes_and_paper_gauge():
    eq = circle(1.0, 0.1, grid=33, kstar=5.0)
    s = spectrum(eq.energy, eq.curve, gauge="paper")
    fig, axes = plotting.new_figure(ncols=2)
    assert plotting.plot_spectrum(s, axes) is axes[0]
    gaps, size = tick_gaps(axes[0], "x")
    assert gaps.min() > 0.9 * size
    assert overlapping_tick_labels(fig) == []
    fig1, ax1 = plotting.new_figure()
    plotting.plot_spectrum(spectrum(eq.energy, eq.curve), ax1)  # one Axes: overview only
    assert len(fig1.axes) == 1


def test_eigenmode_panel_has_a_y_label(triangle_spectrum):
    eq, s = triangle_spectrum
    fig = plotting.plot_eigenmode(s, eq.curve, index=0)
    assert "kappa" in fig.axes[0].get_ylabel()
    assert fig.axes[1].get_ylabel() == "y"


def test_front_count_ticks_are_integers():
    t = np.geomspace(1e-5, 1.0, 50)
    # few fronts: matplotlib's default locator would put ticks at 0.5, 1.5, ...
    fronts = np.repeat([3, 2, 2, 1, 1], 10)
    fig = plotting.plot_front_count(t, fronts)
    fig.canvas.draw()
    lo, hi = fig.axes[0].get_ylim()
    ticks = [y for y in fig.axes[0].get_yticks() if lo <= y <= hi]
    assert {1, 2, 3} <= set(ticks) and np.allclose(ticks, np.round(ticks))


@pytest.fixture(scope="module")
def short_flow():
    th = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    r = 1 + 0.05 * np.cos(5 * th)
    return solve_flow(FacetingFlow(0.1, 5.0, 5.0, 7.0), (r * np.cos(th), r * np.sin(th)), 2e-4,
                      N=64, t_eval=np.linspace(0, 2e-4, 7), progress=False)


def test_animate_flow_writes_one_frame_per_snapshot(short_flow, tmp_path):
    path = tmp_path / "flow.gif"
    anim = plotting.animate_flow(short_flow, path, fps=5)
    assert Image.open(path).n_frames == len(short_flow.t) == 7
    assert anim is not None
    with pytest.raises(ValueError, match="gif or .mp4"):
        plotting.animate_flow(short_flow, tmp_path / "flow.avi")
    with pytest.raises(ValueError, match="fps"):
        plotting.animate_flow(short_flow, fps=0)


def test_flow_command_writes_a_movie(tmp_path, capsys):
    movie = tmp_path / "facet.gif"
    assert main(["flow", "facet", "--N", "48", "--shape", "wobbly", "--t-final", "1e-4",
                 "--tol", "1e-3", "--snapshots", "8", "--movie", str(movie), "--json",
                 "--no-progress"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["movie"] == str(movie)
    assert Image.open(movie).n_frames == 8


def test_flow_command_refuses_a_bad_movie_before_running(tmp_path, capsys):
    assert main(["flow", "facet", "--N", "48", "--movie", str(tmp_path / "m.webm"),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "movie" in err and ".gif" in err and err.count("\n") == 1
