"""Curves and curvature profiles; shared figure helpers.

Figures are built with ``matplotlib.figure.Figure`` and the Agg canvas, so no
global backend is switched and nothing needs a display; pass ``ax`` to draw into
an existing figure (e.g. in a notebook).
"""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["new_figure", "plot_curve", "plot_curvature", "plot_curve_and_curvature", "save"]


def new_figure(ncols=1, nrows=1, size=(5.0, 4.0)):
    """A ``Figure`` with an Agg canvas and its axes (a single ``Axes`` or an array)."""
    fig = Figure(figsize=(size[0] * ncols, size[1] * nrows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols)
    return fig, axes


def figure_pair(axes=None, size=(5.0, 4.0)):
    """``(fig, axes)``: a new two-panel figure, or the figure of the given pair of axes."""
    if axes is None:
        return new_figure(ncols=2, size=size)
    return axes[0].figure, axes


def plot_curve(curve, ax=None, color="C0", mark_start=True):
    """Draw the closed curve ``gamma`` (equal aspect); the open circle marks ``gamma(0)``."""
    if ax is None:
        _, ax = new_figure()
    x, y = curve.positions()
    ax.plot(np.append(x, x[0]), np.append(y, y[0]), color=color, lw=1.5)
    if mark_start:
        ax.plot(x[0], y[0], "o", mfc="none", color=color)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    return ax


def plot_curvature(curve, ax=None, color="C1"):
    """Draw ``kappa(s)`` on ``s in [0, 1)``."""
    if ax is None:
        _, ax = new_figure()
    s = curve.grid.s
    ax.plot(np.append(s, 1.0), np.append(curve.kappa, curve.kappa[0]), color=color, lw=1.2)
    ax.set_xlabel("s")
    ax.set_ylabel(r"$\kappa$")
    ax.set_xlim(0, 1)
    return ax


def plot_curve_and_curvature(curve, axes=None, title=None):
    """The curve (left) and its curvature ``kappa(s)`` (right).

    Parameters
    ----------
    curve : Curve
    axes : pair of Axes, optional
    title : str, optional

    Returns
    -------
    Figure
    """
    fig, axes = figure_pair(axes)
    plot_curve(curve, axes[0])
    plot_curvature(curve, axes[1])
    if title:
        fig.suptitle(title)
    return fig


def save(fig, path, dpi=120):
    """Write ``fig`` to ``path`` (format from the extension)."""
    fig.savefig(path, dpi=dpi)
    return path
