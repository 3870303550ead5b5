"""Bifurcation diagrams: branches against their parameter, stability and shapes."""

from __future__ import annotations

import numpy as np

from qsa.continuation import Branch
from qsa.plotting._core import new_figure

__all__ = ["bifurcation_diagram"]

_LABELS = {"mode": "m", "bloch": "b", "none": "s"}


def _measure(branch, measure):
    if callable(measure):
        return np.array([float(measure(p)) for p in branch.points])
    if measure == "energy":
        return branch.energies()
    if measure == "L":
        return branch.lengths
    raise ValueError(f"measure must be 'energy', 'L' or a callable (BranchPoint) -> float, "
                     f"got {measure!r}")


def _point_measure(eq, measure):
    if callable(measure):
        return None
    return float(eq.energy.energy(eq.curve)) if measure == "energy" else eq.curve.length()


def bifurcation_diagram(branches, measure="energy", ax=None, insets=True, colors=None):
    """Draw branches: stable solid, unstable dashed, markers at bifurcations, shape insets.

    Parameters
    ----------
    branches : Branch or sequence of Branch
    measure : {"energy", "L"} or callable
        The ordinate: the energy of each point, its length, or ``f(BranchPoint)``.
    ax : matplotlib Axes, optional
    insets : bool
        Draw the shape of the last point of each branch in a small inset.
    colors : sequence, optional
        One colour per branch (default the property cycle).

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 5.4, -0.1))
    >>> ax = bifurcation_diagram(b)
    >>> ax.get_xlabel(), len(ax.child_axes) == 1
    ('L_star', True)
    """
    if isinstance(branches, Branch):
        branches = [branches]
    branches = [b for b in branches if b.points]
    if ax is None:
        _, ax = new_figure(size=(6.0, 4.5))
    for j, br in enumerate(branches):
        color = colors[j] if colors is not None else f"C{j % 10}"
        x = br.values
        y = _measure(br, measure)
        nu = br.n_unstable
        stable = np.ones(x.size, bool) if nu is None else nu == 0
        # a segment per run of equal stability, joined at the located bifurcations
        cuts = {}
        for bif in br.bifurcations:
            yb = _point_measure(bif.equilibrium, measure)
            if yb is not None and bif.index < x.size - 1:
                cuts.setdefault(bif.index, (bif.parameter, yb))
        edges = [0] + [i + 1 for i in range(x.size - 1) if stable[i + 1] != stable[i]]
        edges.append(x.size)
        for r in range(len(edges) - 1):
            lo, hi = edges[r], edges[r + 1]
            xs, ys = list(x[lo:hi]), list(y[lo:hi])
            if r > 0:
                joint = cuts.get(lo - 1, (x[lo - 1], y[lo - 1]))
                xs.insert(0, joint[0])
                ys.insert(0, joint[1])
            if hi < x.size and hi - 1 in cuts:
                xs.append(cuts[hi - 1][0])
                ys.append(cuts[hi - 1][1])
            ls = "-" if (nu is None or stable[lo]) else "--"
            ax.plot(xs, ys, ls=ls, color=color, lw=1.6, label=f"branch {j}" if r == 0 else None)
        if br.origin is not None and _point_measure(br.origin.equilibrium, measure) is not None:
            o = br.origin
            ax.plot([o.parameter, x[0]], [_point_measure(o.equilibrium, measure), y[0]],
                    ls="-" if stable[0] else "--", color=color, lw=1.6)
        for b in br.bifurcations:
            yb = _point_measure(b.equilibrium, measure)
            if yb is None:
                continue
            marker = "s" if b.kind == "fold" else ("D" if b.multiplicity == 2 else "o")
            ax.plot(b.parameter, yb, marker, color="k", mfc="w" if b.kind == "fold" else "k",
                    ms=5, zorder=5)
            if b.modes:
                ax.annotate(f"{_LABELS[b.modes[0].label]}={b.sector}", (b.parameter, yb),
                            textcoords="offset points", xytext=(4, 4), fontsize=7)
    if branches:
        ax.set_xlabel(branches[0].param)
    ax.set_ylabel({"energy": "energy", "L": "length L"}.get(measure, "measure")
                  if not callable(measure) else "measure")
    if insets:
        _insets(ax, branches, measure, colors)
    return ax


def _insets(ax, branches, measure, colors):
    """The shape of each branch's last point in a small inset near it."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    for j, br in enumerate(branches):
        p = br.points[-1]
        xv = p.param
        yv = _measure(br, measure)[-1]
        fx = np.clip((xv - x0) / (x1 - x0 or 1.0), 0.02, 0.80)
        fy = np.clip((yv - y0) / (y1 - y0 or 1.0), 0.02, 0.78)
        ins = ax.inset_axes([fx, fy, 0.18, 0.18])
        xy = p.curve.positions()
        color = colors[j] if colors is not None else f"C{j % 10}"
        ins.plot(np.append(xy[0], xy[0][0]), np.append(xy[1], xy[1][0]), color=color, lw=1)
        ins.set_aspect("equal")
        ins.set_xticks([])
        ins.set_yticks([])
