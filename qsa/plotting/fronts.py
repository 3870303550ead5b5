"""Front tracks: DAE flow against the front-position ODE (``qsa reproduce fronts``)."""

from __future__ import annotations

import numpy as np

from qsa.plotting._core import figure_pair, new_figure

__all__ = ["plot_front_tracks", "plot_coarsening"]


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


def plot_coarsening(comparison, ax=None, title=None):
    """Front positions through a whole coarsening: DAE (solid) and front ODE (dashed).

    Parameters
    ----------
    comparison : CoarseningComparison
        From :func:`qsa.paper.compare_coarsening`: positions of the fronts at the
        hand-over (drift removed) against ``t``, log scale from the hand-over on;
        the events are marked (DAE: grey lines, ODE: dotted).
    ax : Axes, optional
    title : str, optional

    Returns
    -------
    Figure
    """
    c = comparison
    if ax is None:
        fig, ax = new_figure(size=(7.0, 4.5))
    else:
        fig = ax.figure
    t0 = c.handover_time
    x_dae = np.maximum(c.t_dae - t0, 1e-12)
    x_ode = np.maximum(c.t_ode - t0, 1e-12)
    for i in range(c.dae_positions.shape[1]):
        color = f"C{i % 10}"
        ax.plot(x_dae, c.dae_positions[:, i], "-", color=color, lw=1.6,
                label="DAE" if i == 0 else None)
        ax.plot(x_ode, c.ode_positions[:, i], "--", color="k", lw=0.9,
                label="front ODE" if i == 0 else None)
    for events, style in ((c.dae_events, "-"), (c.ode_events, ":")):
        for e in events:
            ax.axvline(e.time - t0, color="0.6", ls=style, lw=0.8)
    ax.set_xscale("log")
    ax.set_xlim(left=max(1e-3 * (c.t_final - t0), x_dae[1] if x_dae.size > 1 else 1e-9))
    ax.set_xlabel(f"t - {t0:.3g} (time since the hand-over)")
    ax.set_ylabel("front position (drift removed)")
    ax.legend(fontsize=7, loc="best")
    if title:
        ax.set_title(title)
    return fig
