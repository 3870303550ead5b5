"""Front tracks: DAE flow against the front-position ODE (``qsa reproduce fronts``)."""

from __future__ import annotations

import numpy as np

from qsa.plotting._core import figure_pair

__all__ = ["plot_front_tracks"]


def plot_front_tracks(comparison, axes=None, title=None):
    """Front positions ``p_i(t)`` of the DAE (solid) and the ODE (dashed), and their error.

    Parameters
    ----------
    comparison : FrontComparison
        From :func:`qsa.paper.compare_fronts`.
    axes : pair of Axes, optional
        Left: positions (zero mean) against t with the collision times; right:
        the position error / smallest facet against ``t / t_c`` (DAE).
    title : str, optional

    Returns
    -------
    Figure
    """
    c = comparison
    fig, axes = figure_pair(axes)
    ax = axes[0]
    for i in range(c.dae.shape[1]):
        color = f"C{i % 10}"
        ax.plot(c.t, c.dae[:, i], "-", color=color, lw=1.6,
                label="DAE" if i == 0 else None)
        ax.plot(c.t_ode, c.p_ode[:, i], "--", color="k", lw=0.9,
                label="ODE" if i == 0 else None)
    for tc, style, name in ((c.collision_dae, "-", "DAE"), (c.collision_ode, ":", "ODE")):
        if np.isfinite(tc):
            ax.axvline(tc, color="0.5", ls=style, lw=0.8, label=f"collision ({name})")
    ax.set_xlabel("t")
    ax.set_ylabel("front position (zero mean)")
    ax.legend(fontsize=7, loc="best")
    ax = axes[1]
    if np.isfinite(c.collision_dae):
        x = c.t / c.collision_dae
        ok = np.isfinite(c.error) & (c.error > 0)
        ax.semilogy(x[ok], c.error[ok], "o-", ms=2, lw=1)
        ax.axhline(0.05, color="0.5", ls="--", lw=0.8, label="5% of smallest facet")
        ax.set_xlabel(r"$t / t_c^{\mathrm{DAE}}$")
        ax.legend(fontsize=7)
    ax.set_ylabel("max position error / smallest facet")
    if title:
        fig.suptitle(title)
    return fig
