"""Figures of the paper's simulations (f:facet, f:facet_energy, f:Snowflake, f:fold).

The drawing functions take plain arrays; ``facet_figures``, ``cha_figures``
and ``folding_figure`` take the results of :func:`qsa.paper.run_facet` and
:func:`qsa.paper.run_cha` (:class:`qsa.paper.FacetRun`, :class:`qsa.paper.CHARun`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.ticker import MaxNLocator

from qsa.plotting._core import new_figure

__all__ = [
    "folded_modes_figure",
    "plot_facet_panels",
    "plot_energy_residual",
    "plot_front_count",
    "plot_shaded_curve",
    "plot_energy_history",
    "facet_figures",
    "cha_figures",
    "folding_figure",
    "spacing_figure",
]


def _nearest(times, t):
    return int(np.argmin(np.abs(np.asarray(times) - t)))


def _reached(times, snap_t, t_reached, n=5):
    """The requested times the run reached, or ``n`` snapshots spread over a short run."""
    out = [t for t in times if t <= t_reached * 1.0001]
    if len(out) >= 2:
        return out
    snap_t = np.asarray(snap_t)
    return list(snap_t[np.unique(np.linspace(0, snap_t.size - 1, n).round().astype(int))])


def _column_times(times, snap_t):
    """Column times within the run; if one lies past its end, all become log-spaced in it."""
    times = list(times)
    t_end = float(snap_t[-1])
    if all(t is None or t <= t_end for t in times):
        return times
    pos = snap_t[snap_t > 0]
    t_lo = float(pos[0]) if pos.size else t_end
    k = sum(t is not None for t in times)
    fill = iter(np.geomspace(t_lo, t_end, k + 2)[1:-1])
    return [None if t is None else float(next(fill)) for t in times]


def _closed(a):
    return np.append(a, a[0])


def plot_facet_panels(snap_t, xs, ys, kappas, times, kstar=None):
    """Curves (top row) and ``kappa(s)`` (bottom row) at the snapshots nearest ``times``.

    The open circle marks ``gamma(0)`` (as in f:facet).

    Parameters
    ----------
    snap_t : ndarray, shape (n,)
    xs, ys, kappas : ndarray, shape (n, N)
    times : sequence of float
    kstar : float, optional
        Draws the wells ``0`` and ``kappa*`` as dotted lines.

    Returns
    -------
    Figure
    """
    fig, axes = new_figure(ncols=len(times), nrows=2, size=(2.6, 2.4))
    axes = np.atleast_2d(axes).reshape(2, len(times))
    N = np.shape(kappas)[1]
    s = np.arange(N + 1) / N
    for col, t in enumerate(times):
        i = _nearest(snap_t, t)
        ax = axes[0, col]
        ax.plot(_closed(xs[i]), _closed(ys[i]), color="C0", lw=1.2)
        ax.plot(xs[i][0], ys[i][0], "o", mfc="none", color="C0")
        ax.set_aspect("equal")
        ax.set_title(f"t = {snap_t[i]:.3g}", fontsize=9)
        ax.tick_params(labelsize=7)
        ax = axes[1, col]
        ax.plot(s, _closed(kappas[i]), color="C1", lw=1.0)
        if kstar is not None:
            for level in (0.0, kstar):
                ax.axhline(level, color="0.6", ls=":", lw=0.8)
        ax.set_xlim(0, 1)
        ax.set_xlabel("s", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[1, 0].set_ylabel(r"$\kappa$")
    return fig


def _time_axes(ax, size, t, events):
    """Figure/axes with a log time axis, the ``t > 0`` mask and dashed event lines."""
    if ax is None:
        fig, ax = new_figure(size=size)
    else:
        fig = ax.figure
    ax.set_xscale("log")
    ax.set_xlabel("t")
    for te in events:
        ax.axvline(te, color="0.7", lw=0.6, ls="--")
    t = np.asarray(t, dtype=float)
    return fig, ax, t, t > 0


def plot_energy_residual(t, energy, residual, events=(), ax=None):
    """Energy (blue) and functional residual ``R_kappa`` (red), log scale, vs time (f:facet_energy).

    Time is drawn on a log axis as well (the events span five decades);
    ``events`` are marked by vertical lines.
    """
    fig, ax, t, keep = _time_axes(ax, (6.0, 4.0), t, events)
    ax.semilogy(t[keep], np.asarray(energy)[keep], color="C0", label="energy")
    ax.set_ylabel("energy", color="C0")
    ax2 = ax.twinx()
    ax2.semilogy(t[keep], np.asarray(residual)[keep], color="C3", lw=0.8,
                 label=r"$R_\kappa$")
    ax2.set_ylabel(r"$R_\kappa = \max|\mu - \langle\mu\rangle|$", color="C3")
    return fig


def plot_front_count(t, fronts, events=(), ax=None):
    """Number of fronts (crossings of ``kappa*/2``) against time (log time axis)."""
    fig, ax, t, keep = _time_axes(ax, (6.0, 3.0), t, events)
    ax.step(t[keep], np.asarray(fronts)[keep], where="post", color="C2")
    ax.set_ylabel("fronts")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    return fig


def plot_shaded_curve(x, y, ax=None, title=None, color="C0"):
    """A closed curve with its interior shaded (f:Snowflake, f:fold).

    The interior is filled with the even-odd rule, so a self-intersecting
    polygon shows its overlap unshaded.
    """
    if ax is None:
        _, ax = new_figure(size=(3.0, 3.0))
    ax.fill(_closed(x), _closed(y), color=color, alpha=0.35, lw=0)
    ax.plot(_closed(x), _closed(y), color=color, lw=0.6)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    return ax


def plot_energy_history(t, energy, ax=None, label=None, color="C0"):
    """Semi-log energy against time (log time axis; ``t > 0`` only)."""
    if ax is None:
        fig, ax = new_figure(size=(6.0, 3.0))
    else:
        fig = ax.figure
    t = np.asarray(t, dtype=float)
    keep = t > 0
    ax.plot(t[keep], np.asarray(energy)[keep], color=color, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log" if np.all(np.asarray(energy)[keep] > 0) else "linear")
    ax.set_xlabel("t")
    ax.set_ylabel("energy")
    return fig


# ------------------------------------------------------------ run results
def facet_figures(run):
    """The figures of a :class:`qsa.paper.FacetRun`: ``{"panels", "energy", "fronts"}``."""
    sc = run.scenario
    N = int(sc.N)
    Y = np.asarray(run.snap_states)
    xs, ys, ks = Y[:, :N], Y[:, N : 2 * N], Y[:, 2 * N : 3 * N]
    times = _reached(sc.physical_figure_times, run.snap_t, run.t_reached)
    events = [e.t for e in run.coarsening.events]
    panels = plot_facet_panels(run.snap_t, xs, ys, ks, times, kstar=sc.kstar)
    panels.suptitle(f"faceting coarsening: alpha={sc.alpha:g}, beta={sc.beta:g}, "
                    f"kappa*={sc.kstar:g}, N={N}")
    energy = plot_energy_residual(run.t, run.energy, run.R_kappa, events)
    fronts = plot_front_count(run.t, run.fronts, events)
    return {"panels": panels, "energy": energy, "fronts": fronts}


def cha_figures(run, times=None):
    """The figures of a :class:`qsa.paper.CHARun`: ``{"snapshots"}`` (f:Snowflake layout).

    Snapshots at ``times`` (default: the scenario's figure times), shaded,
    three per row, and the energy against time below.
    """
    sc = run.scenario
    times = list(sc.figure_times if times is None else times)
    times = _reached(times, run.snap_t, run.t_reached)
    ncols = 3
    nrows = -(-len(times) // ncols)
    fig, axes = new_figure(ncols=ncols, nrows=nrows + 1, size=(3.0, 3.0))
    axes = np.atleast_2d(axes)
    snap_t = np.asarray(run.snap_t)
    xs, ys = np.asarray(run.snap_x), np.asarray(run.snap_y)
    for k, ax in enumerate(axes[:nrows].ravel()):
        if k >= len(times):
            ax.set_visible(False)
            continue
        if times[k] == 0:
            x, y, t = run.x0, run.y0, 0.0
        else:
            i = _nearest(snap_t, times[k])
            x, y, t = xs[i], ys[i], snap_t[i]
        plot_shaded_curve(x, y, ax=ax, title=f"t = {t:.4g}")
    gs = axes[-1, 0].get_gridspec()
    for ax in axes[-1]:
        ax.remove()
    ax = fig.add_subplot(gs[-1, :])
    plot_energy_history(run.t_steps, run.energy_steps, ax=ax)
    source = (f"Table T1, l* = {sc.l_star:g}" if sc.l_star in (0.1, 0.01)
              else f"Table T1 but l* = {sc.l_star:g}")
    fig.suptitle(f"CHA flow, rho = {sc.rho:g} ({source}), N = {run.N}")
    return {"snapshots": fig}


def folding_figure(runs, times=(0.02, 0.3, None)):
    """f:fold: rows = runs (increasing rho), columns = short, mid and final time; energies below.

    A run that crossed itself shows, in its first column, the state at its first
    self-intersection with the crossing points marked (the paper's "glancing
    self-intersection in the short-time column").

    Parameters
    ----------
    runs : sequence of CHARun
    times : sequence
        Column times; ``None`` means the final state. Times beyond a run's end
        are replaced by log-spaced times between its first snapshot and its end.
    """
    nrows = len(runs)
    fig, axes = new_figure(ncols=len(times), nrows=nrows + 1, size=(3.0, 3.0))
    axes = np.atleast_2d(axes)
    for r, run in enumerate(runs):
        snap_t = np.asarray(run.snap_t)
        for c, t in enumerate(_column_times(times, snap_t)):
            ax = axes[r, c]
            fc = run.first_crossing
            if c == 0 and fc is not None:
                plot_shaded_curve(fc.x, fc.y, ax=ax,
                                  title=f"rho={run.rho:g}, t={fc.t:.3g} (crossing)",
                                  color=f"C{r}")
                pts = np.atleast_2d(fc.points)
                ax.plot(pts[:, 0], pts[:, 1], "o", mfc="none", mec="red", ms=9, mew=1.5)
                continue
            i = len(snap_t) - 1 if t is None else _nearest(snap_t, t)
            plot_shaded_curve(run.snap_x[i], run.snap_y[i], ax=ax,
                              title=f"rho={run.rho:g}, t={snap_t[i]:.3g}", color=f"C{r}")
    gs = axes[-1, 0].get_gridspec()
    for ax in axes[-1]:
        ax.remove()
    ax = fig.add_subplot(gs[-1, :])
    for r, run in enumerate(runs):
        plot_energy_history(run.t_steps, run.energy_steps, ax=ax, label=f"rho={run.rho:g}",
                            color=f"C{r}")
    ax.legend(fontsize=8)
    return fig


def folded_modes_figure(results, n_modes=2, size=3.2):
    """The slowest modes of polished folded states, coloured on their curves.

    One row per result (a :class:`qsa.paper.folded.FoldedEquilibrium` with a
    spectrum), one column per mode (the ``n_modes`` non-kernel eigenvalues nearest 0):
    the curve coloured by the eigenvector ``phi`` (normal gauge, scaled to max 1).
    """
    rows = [r for r in results if r.spectrum is not None]
    fig, axes = new_figure(ncols=n_modes, nrows=max(len(rows), 1),
                           size=(size, size))
    axes = np.atleast_2d(axes).reshape(max(len(rows), 1), n_modes)
    for r, row in zip(rows, axes, strict=False):
        x, y = r.curve.positions()
        pts = np.column_stack([_closed(x), _closed(y)])
        segs = np.stack([pts[:-1], pts[1:]], axis=1)
        for j, ax in enumerate(row):
            ax.set_aspect("equal")
            ax.axis("off")
            if j >= len(r.slowest):
                continue
            i = r.slowest[j]
            phi = r.spectrum.eigenvectors[:, i]
            phi = phi / np.abs(phi).max()
            lc = LineCollection(segs, cmap="coolwarm", norm=None)
            lc.set_array(phi)
            lc.set_clim(-1, 1)
            lc.set_linewidth(1.5)
            ax.add_collection(lc)
            ax.autoscale_view()
            ax.set_title(rf"{r.name}: $\lambda$ = {r.spectrum.eigenvalues[i]:.4g}", fontsize=8)
    return fig


def spacing_figure(sweep, size=(4.6, 3.4)):
    """The paired sheets of a near-contact sweep and their spacing along the pair.

    Left: each polished equilibrium (stacked, labelled by ``l*``). Right:
    ``|spacing / d* - 1|`` along the longest pair against the distance from its nearer
    end, with the decay ``exp(-x / length)`` of the predicted relaxation length
    (dashed, through the largest maximum below ``1e-2``).

    Parameters
    ----------
    sweep : qsa.paper.near_contact.NearContactSweep
    """
    fig, (left, right) = new_figure(ncols=2, size=size)
    offset = 0.0
    profiles = sweep.profiles()
    for k, (p, c, prof) in enumerate(zip(sweep.points, sweep.curves, profiles, strict=True)):
        color = f"C{k}"
        x, y = c.positions()
        xc, yc = x - x.mean(), y - y.mean()
        _, _, vt = np.linalg.svd(np.column_stack([xc, yc]), full_matrices=False)
        u, v = (np.column_stack([xc, yc]) @ vt.T).T
        left.plot(_closed(u), _closed(v) - v.max() - offset, color=color, lw=1)
        left.text(u.max(), -offset - v.max(), rf" $\ell_*$ = {p.l_star:g}", fontsize=7,
                  color=color, va="center")
        offset += np.ptp(v) + 0.1
        if prof is None:
            continue
        arc, d = prof
        dist = np.minimum(arc, arc[-1] - arc)
        r = np.abs(d / p.target - 1)
        order = np.argsort(dist)
        right.semilogy(dist[order], r[order], ".", ms=1.5, color=color)
        below = r < 1e-2
        if below.any() and np.isfinite(p.predicted_decay):
            i = np.flatnonzero(below)[np.argmax(r[below])]
            xs = np.linspace(dist[i], dist.max(), 20)
            right.semilogy(xs, r[i] * np.exp(-(xs - dist[i]) / p.predicted_decay), "--",
                           color=color, lw=0.8)
    left.set_aspect("equal")
    left.axis("off")
    right.set_xlabel("distance from the end of the pair")
    right.set_ylabel(r"$|d / d^* - 1|$")
    right.set_ylim(1e-11, 1)
    return fig
