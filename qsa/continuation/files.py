"""Branches on disk: a CSV table and a JSON summary per branch, the curves in one ``.npz``.

For a branch saved under ``stem`` in ``folder``:

``stem.csv``
    One row per point: ``index, parameter, L, energy, n_unstable, stable, residual``
    (``n_unstable`` empty without stability).
``stem.json``
    :meth:`Branch.summary` (status, message, folds, bifurcations with their parameter,
    multiplicity, kind and symmetry label).
``stem.npz``
    The curves (:func:`qsa.io.save_npz`, atomic): ``kappa`` and ``g`` of shape
    ``(n_points, N)``, ``theta0`` and ``origin`` per point, ``parameter``; the
    bifurcation curves as ``bif_kappa``, ``bif_g``, ``bif_parameter``; the summary as
    metadata.
"""

from __future__ import annotations

import csv
import json
import os

import numpy as np

from qsa.continuation.branch import Branch
from qsa.npz import json_default, save_npz

__all__ = ["save_branch", "save_branches"]


def _energies(branch):
    try:
        return branch.energies()
    except (ValueError, ArithmeticError):
        return np.full(len(branch.points), np.nan)


def save_branch(branch: Branch, folder, stem="branch") -> dict:
    """Write ``stem.csv``, ``stem.json`` and ``stem.npz`` of ``branch`` into ``folder``.

    Parameters
    ----------
    branch : Branch
    folder : str or os.PathLike
        Created if missing.
    stem : str

    Returns
    -------
    dict
        ``{"csv": path, "json": path, "npz": path}``.

    Examples
    --------
    >>> import os, tempfile
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 5.7, -0.1))
    >>> paths = save_branch(b, tempfile.mkdtemp())
    >>> sorted(paths), open(paths["csv"]).readline().strip()
    (['csv', 'json', 'npz'], 'index,parameter,L,energy,n_unstable,stable,residual')
    """
    if not isinstance(branch, Branch):
        raise ValueError(f"branch must be a Branch, got {type(branch).__name__}")
    folder = os.fspath(folder)
    os.makedirs(folder, exist_ok=True)
    base = os.path.join(folder, stem)
    nu = branch.n_unstable
    energies = _energies(branch)
    with open(base + ".csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "parameter", "L", "energy", "n_unstable", "stable", "residual"])
        for i, p in enumerate(branch.points):
            w.writerow([i, repr(float(p.param)), repr(float(p.curve.length())),
                        repr(float(energies[i])), "" if nu is None else int(nu[i]),
                        "" if nu is None else int(nu[i] == 0),
                        repr(float(p.equilibrium.residual))])
    summary = branch.summary()
    with open(base + ".json", "w") as fh:
        json.dump(summary, fh, indent=2, default=json_default)
    pts = branch.points
    N = pts[0].curve.N if pts else 0
    bifs = branch.bifurcations
    arrays = {
        "parameter": branch.values,
        "kappa": np.array([p.curve.kappa for p in pts]).reshape(len(pts), N),
        "g": np.array([p.curve.g for p in pts]).reshape(len(pts), N),
        "theta0": np.array([p.curve.theta0 for p in pts], dtype=float),
        "origin": np.array([p.curve.origin for p in pts], dtype=float).reshape(len(pts), 2),
        "bif_parameter": np.array([b.parameter for b in bifs], dtype=float),
        "bif_kappa": np.array([b.curve.kappa for b in bifs]).reshape(len(bifs), N),
        "bif_g": np.array([b.curve.g for b in bifs]).reshape(len(bifs), N),
    }
    grid = pts[0].curve.grid if pts else None
    meta = {"kind": "branch", "grid": None if grid is None else repr(grid), **summary}
    save_npz(base + ".npz", arrays, meta)
    return {"csv": base + ".csv", "json": base + ".json", "npz": base + ".npz"}


def save_branches(branches, folder, stem="branch") -> list:
    """:func:`save_branch` for each branch as ``stem0``, ``stem1``, ...; returns their paths."""
    return [save_branch(b, folder, f"{stem}{i}") for i, b in enumerate(branches)]
