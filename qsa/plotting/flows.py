"""Figures for curve flows: snapshots, energy/length histories, convergence and step counts."""

from __future__ import annotations

import numpy as np

from qsa.plotting._core import figure_pair, new_figure

__all__ = ["plot_flow", "plot_energy_and_length", "plot_convergence", "plot_timesteps"]


def plot_flow(result, axes=None, max_curves=6, title=None):
    """Snapshots of the curve (left) and the energy history (right) of a ``FlowResult``.

    Parameters
    ----------
    result : FlowResult
    axes : pair of Axes, optional
    max_curves : int
        Largest number of snapshots drawn (evenly chosen, first and last included).
    title : str, optional

    Returns
    -------
    Figure
    """
    fig, axes = figure_pair(axes)
    n = len(result.t)
    pick = np.unique(np.linspace(0, n - 1, min(max_curves, n)).round().astype(int))
    ax = axes[0]
    for rank, i in enumerate(pick):
        x, y = result.positions(i)
        shade = 0.25 + 0.75 * rank / max(len(pick) - 1, 1)
        ax.plot(np.append(x, x[0]), np.append(y, y[0]), color=(0.1, 0.2, 0.6, shade),
                lw=1.2, label=f"t = {result.t[i]:.3g}")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.legend(fontsize="small", loc="best")
    plot_energy_and_length(result, axes[1])
    if title:
        fig.suptitle(title)
    return fig


def plot_energy_and_length(result, ax=None):
    """Energy after every accepted step (and the length on a twin axis) of a ``FlowResult``.

    (:func:`qsa.plotting.plot_energy_history` draws an energy against time on log axes.)
    """
    if ax is None:
        _, ax = new_figure()
    ax.plot(result.t_steps, result.energy_steps, color="C0", lw=1.5, label="energy")
    ax.set_xlabel("t")
    ax.set_ylabel("energy", color="C0")
    twin = ax.twinx()
    twin.plot(result.t_steps, result.length_steps, color="C1", lw=1.0, ls="--")
    twin.set_ylabel("length L", color="C1")
    return ax


def plot_convergence(Ns, differences, paper=None, ax=None, label="qsa"):
    """``max |X(2N) - X(N)|`` against N on log axes, with the paper's table if given.

    Parameters
    ----------
    Ns : sequence of int
    differences : sequence of float
    paper : dict, optional
        ``{N: difference}`` of the paper (Table ap:t1).
    """
    if ax is None:
        _, ax = new_figure()
    Ns = np.asarray(Ns, float)
    d = np.asarray(differences, float)
    ax.loglog(Ns, d, "o-", label=label)
    if paper:
        pN = np.array(sorted(paper), float)
        ax.loglog(pN, [paper[int(n)] for n in pN], "s--", label="paper (Table ap:t1)")
    ax.loglog(Ns, d[0] * (Ns[0] / Ns) ** 2, ":", color="gray", label="slope -2")
    ax.set_xlabel("N")
    ax.set_ylabel(r"$\max\,|X(2N) - X(N)|$")
    ax.legend(fontsize="small")
    return ax


def plot_timesteps(tols, steps, paper=None, ax=None, labels=None):
    """Accepted steps against the tolerance (log-log), one line per method."""
    if ax is None:
        _, ax = new_figure()
    tols = np.asarray(tols, float)
    series = steps if isinstance(steps, dict) else {labels or "qsa": steps}
    for name, values in series.items():
        ax.loglog(tols, values, "o-", label=name)
    if paper is not None:
        ax.loglog(tols, paper, "s--", label="paper")
    ax.loglog(tols, np.asarray(paper if paper is not None else list(series.values())[0],
                               float)[0] * (tols[0] / tols) ** 0.5, ":", color="gray",
              label=r"$\propto$ tol$^{-1/2}$")
    ax.invert_xaxis()
    ax.set_xlabel("tolerance")
    ax.set_ylabel("steps")
    ax.legend(fontsize="small")
    return ax
