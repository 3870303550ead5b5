"""Figures of parameter sweeps (:mod:`qsa.sweep`): a result column against a parameter."""

from __future__ import annotations

import numpy as np

from qsa.plotting._core import new_figure

__all__ = ["plot_sweep"]


def plot_sweep(result, x, y, hue=None, ax=None, logy=None, title=None):
    """Plot column ``y`` against parameter ``x``, one line per value of ``hue``.

    Parameters
    ----------
    result : SweepResult or list of dict
        A :class:`qsa.sweep.SweepResult` or rows as from :func:`qsa.sweep.read_table`.
    x, y : str
        Column names (``y`` numeric; failed points are skipped).
    hue : str, optional
        Column whose values split the rows into lines (default: all the other
        parameters of a SweepResult with more than one value, combined).
    ax : Axes, optional
    logy : bool, optional
        Log scale for ``|y|``; default when the positive values span > 3 decades.
    title : str, optional

    Returns
    -------
    Figure
    """
    rows = result.rows if hasattr(result, "rows") else list(result)
    if not rows:
        raise ValueError("result: no rows to plot")
    for name in (x, y) + ((hue,) if hue else ()):
        if name not in rows[0]:
            raise ValueError(f"column {name!r} not in the table (have {list(rows[0])})")
    if hue is None and hasattr(result, "columns"):
        params = result.columns[: result.columns.index("success")]
        others = [p for p in params if p != x and len({r[p] for r in rows}) > 1]
    else:
        others = [hue] if hue else []
    if ax is None:
        fig, ax = new_figure()
    else:
        fig = ax.figure
    groups = {}
    for r in rows:
        if not r.get("success", True):
            continue
        groups.setdefault(tuple(r[o] for o in others), []).append(r)
    ys_all = []
    for label, grp in sorted(groups.items(), key=lambda kv: str(kv[0])):
        grp = sorted(grp, key=lambda r: r[x])
        xs = np.array([r[x] for r in grp], dtype=float)
        ys = np.array([r[y] for r in grp], dtype=float)
        ys_all.append(ys)
        name = ", ".join(f"{o}={v}" for o, v in zip(others, label, strict=True)) or None
        ax.plot(xs, ys, "o-", ms=3, lw=1.2, label=name)
    if logy is None:
        pos = np.abs(np.concatenate(ys_all)) if ys_all else np.array([])
        pos = pos[np.isfinite(pos) & (pos > 0)]
        logy = pos.size > 1 and pos.max() / pos.min() > 1e3 and bool(
            np.all(np.concatenate(ys_all)[np.isfinite(np.concatenate(ys_all))] > 0))
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if others:
        ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return fig
