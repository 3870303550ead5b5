"""Stability along a branch: counting the unstable eigenvalues and locating where the count changes.

Counting
--------
At every point the eigenvalues of ``J`` (the normal-velocity linearization, kernel
deflated) are computed per Bloch sector of the branch's symmetry
(:func:`qsa.spectra.symmetry.sector_spectrum`) from ONE shift-invert factorization of the
factored operator: for sectors of dimension up to
:data:`~qsa.spectra.symmetry.DENSE_SECTOR_LIMIT` the compressed inverse of each sector is
formed and diagonalised, so *every* eigenvalue of the sector is computed, each with an
error bound, and the count of certified positive ones (``lambda > error``) is exact: no
eigenvalue can be missed, and double eigenvalues (complex sectors) are exact pairs.
Larger sectors use the ``k`` eigenvalues nearest 0 (ARPACK on the sector); the count
is then of those (the branch message says so).

A change of the count of a sector ``b`` between two points brackets a crossing of
that sector; its multiplicity is that of the sector (2 for ``0 < b < n/2``).

Location
--------
The crossing eigenvalue is the ``j``-th largest of its sector, ``j`` the number of
sector eigenvalues above it on the stable side; it is a continuous function of the
position ``t`` along the branch (arclength along the tangent at the left point, or the
parameter for natural continuation). Illinois regula falsi on it, re-polishing the
equilibrium at every trial ``t`` (the corrector of the continuation), stops when the
bracket in the parameter is below ``ptol`` or the eigenvalue is zero within its error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa.continuation.branch import CriticalMode
from qsa.spectra.symmetry import DENSE_SECTOR_LIMIT, BlochSymmetry, sector_spectrum

__all__ = ["StabilityRecord", "count_unstable", "keeps_symmetry", "locate_crossing",
           "critical_modes", "crossing_index", "switching_directions"]

#: Eigenvalues per sector stored at each point (nearest 0).
N_CRITICAL = 3


@dataclass(frozen=True, eq=False)
class StabilityRecord:
    """The unstable count at one point.

    Attributes
    ----------
    n_unstable : int
    sector_unstable : tuple of int
        Per sector ``b = 0..floor(n/2)``, with multiplicity.
    critical : ndarray, shape (m, 2)
        Rows ``(lambda, b)``: the :data:`N_CRITICAL` eigenvalues nearest 0 per sector.
    complete : bool
        Every eigenvalue was computed (the count is exact).
    ambiguous : int
        Eigenvalues zero within their error (sign not certified).

    Parameters
    ----------
    The attributes above.
    """

    n_unstable: int
    sector_unstable: tuple
    critical: np.ndarray
    complete: bool
    ambiguous: int


def keeps_symmetry(curve, symmetry: BlochSymmetry, tol=1e-7) -> bool:
    """Whether ``curve`` still has the symmetry ``symmetry`` (curvature shift-invariant)."""
    if symmetry.order == 1:
        return True
    k = np.asarray(curve.kappa)
    scale = max(float(np.max(np.abs(k))), 1e-300)
    if symmetry.circle:
        return bool(np.ptp(k) <= tol * scale)
    return bool(np.max(np.abs(np.roll(k, -symmetry.shift) - k)) <= tol * scale)


def count_unstable(energy, curve, symmetry: BlochSymmetry, k=None, constraints=None):
    """``(StabilityRecord, SectorSpectrum)`` at an equilibrium (one factorization).

    Parameters
    ----------
    energy : Energy
    curve : Curve
    symmetry : BlochSymmetry
    k : int, optional
        Eigenvalues per sector for sectors too large for the dense path.
    constraints : sequence of Constraint, optional
        Length / area constraints (the constrained operator's spectrum).

    Returns
    -------
    StabilityRecord, SectorSpectrum
    """
    kk = None if symmetry.shift <= DENSE_SECTOR_LIMIT else (k or 8)
    spec = sector_spectrum(energy, curve, symmetry, k=kk, constraints=constraints)
    counts = tuple(spec.n_unstable_in(b) for b in symmetry.sectors)
    rows: list = []
    for b in symmetry.sectors:
        sel = np.flatnonzero(spec.sector == b)
        near = sel[np.argsort(np.abs(spec.eigenvalues[sel]))[:N_CRITICAL]]
        rows.extend((float(spec.eigenvalues[i]), float(b)) for i in near)
    rec = StabilityRecord(int(sum(counts)), counts, np.array(rows).reshape(-1, 2),
                          bool(spec.complete), int(np.sum(spec.ambiguous)))
    return rec, spec


def crossing_index(spec, b, j):
    """Index into ``spec`` of the ``j``-th largest eigenvalue of sector ``b`` (None if absent)."""
    sel = np.flatnonzero(spec.sector == b)
    if j >= sel.size:
        return None
    return int(sel[np.argsort(-spec.eigenvalues[sel], kind="stable")[j]])


def locate_crossing(solve_at, eig_at, t0, t1, f0, f1, ptol=1e-10, maxiter=40):
    """Illinois regula falsi for the zero of the critical eigenvalue between ``t0`` and ``t1``.

    Parameters
    ----------
    solve_at : callable
        ``t -> (equilibrium, p, extra)`` or None when the corrector fails.
    eig_at : callable
        ``(equilibrium) -> (lambda, error, spectrum)``, or None when the eigenvalue is
        not available.
    t0, t1 : float
        Bracket (positions along the branch) with ``f0 * f1 < 0``.
    f0, f1 : float
        The critical eigenvalue at the ends.
    ptol : float
        Stop when the bracket spans less than this in the parameter.
    maxiter : int

    Returns
    -------
    (t, equilibrium, p, lambda, spectrum, extra) or None
        The best point found (smallest ``|lambda|``); None if no trial point solved.
    """
    best = None
    side = 0
    p_lo = p_hi = None
    for _ in range(maxiter):
        t = t1 - f1 * (t1 - t0) / (f1 - f0) if f1 != f0 else 0.5 * (t0 + t1)
        lo, hi = min(t0, t1), max(t0, t1)
        if not (lo < t < hi):
            t = 0.5 * (t0 + t1)
        sol = solve_at(t)
        ev = None if sol is None else eig_at(sol[0])
        if ev is None:
            t = 0.5 * (t0 + t1)
            sol = solve_at(t)
            ev = None if sol is None else eig_at(sol[0])
            if ev is None:
                break
        eq, p, extra = sol
        lam, err, spec = ev
        if best is None or abs(lam) < abs(best[3]):
            best = (t, eq, p, lam, spec, extra)
        if abs(lam) <= err:
            break
        if np.sign(lam) == np.sign(f1):
            t1, f1 = t, lam
            p_hi = p
            if side == 1:
                f0 *= 0.5
            side = 1
        else:
            t0, f0 = t, lam
            p_lo = p
            if side == -1:
                f1 *= 0.5
            side = -1
        if p_lo is not None and p_hi is not None and abs(p_hi - p_lo) <= ptol:
            break
    return best


def _orbit(v, symmetry):
    """Images of ``v`` under the node shifts (and the reflection): the group orbit."""
    out = []
    for j in range(symmetry.order):
        u = np.roll(v, -j * symmetry.shift)
        out.append(u)
        if symmetry.reflection is not None:
            out.append(symmetry.reflect(u))
    return out


def critical_modes(spec, i, symmetry: BlochSymmetry):
    """The :class:`CriticalMode` s of entry ``i`` of a sector spectrum.

    For a double eigenvalue the basis of the critical plane is rotated to the
    reflection-even and reflection-odd vectors when the state has a reflection.
    """
    b = int(spec.sector[i])
    V = spec.real_vectors(i)
    label = "none" if symmetry.order == 1 else symmetry.label()
    if symmetry.reflection is None:
        return tuple(CriticalMode(V[:, j], b, label, 0) for j in range(V.shape[1]))
    w = spec.dsigma
    RV = np.column_stack([symmetry.reflect(V[:, j]) for j in range(V.shape[1])])
    Rm = V.T @ (w[:, None] * RV)
    vals, Y = np.linalg.eigh(0.5 * (Rm + Rm.T))
    Vr = V @ Y
    modes = []
    for j in np.argsort(-vals):
        v = Vr[:, j] / np.sqrt(np.sum(w * Vr[:, j] ** 2))
        modes.append(CriticalMode(v, b, label, int(np.sign(np.round(vals[j])))))
    return tuple(modes)


def switching_directions(bif, symmetry: BlochSymmetry, tol=1e-6):
    """Representatives of the symmetry-distinct directions of a bifurcation's critical space.

    * a circle (O(2)): one direction (every direction of the mode-``m`` plane is a
      rotation of ``cos m theta``);
    * a double eigenvalue with a reflection (D_n): the fixed lines of the reflections
      ``i -> c - i`` and ``i -> c - q - i`` (``q = N/n``; together they meet every class
      of reflection axes), both orientations, one per group orbit;
    * a simple eigenvalue: ``phi`` and ``-phi`` unless a symmetry maps one to the other.

    Returns
    -------
    list of ndarray, shape (N,)
    """
    modes = bif.modes
    if not modes:
        return []
    if symmetry.circle:
        return [modes[0].vector]
    cands = []
    if len(modes) == 2 and symmetry.reflection is not None:
        even = [m.vector for m in modes if m.parity > 0]
        odd = [m.vector for m in modes if m.parity < 0]
        if even:
            cands += [even[0], -even[0]]
        # the fixed line of the reflection c - q: the even vector of that reflection
        shifted = BlochSymmetry(symmetry.order, symmetry.N, False,
                                (symmetry.reflection - symmetry.shift) % symmetry.N)
        V = np.column_stack([m.vector for m in modes])
        RV = np.column_stack([shifted.reflect(V[:, j]) for j in range(2)])
        vals, Y = np.linalg.eigh(0.5 * (V.T @ RV + (V.T @ RV).T))
        e2 = V @ Y[:, int(np.argmax(vals))]
        cands += [e2, -e2]
        if odd and not even:
            cands += [odd[0], -odd[0]]
    else:
        cands = [modes[0].vector, -modes[0].vector]
    kept: list = []
    for v in cands:
        v = v / max(np.linalg.norm(v), 1e-300)
        if not any(min(np.linalg.norm(u / np.linalg.norm(u) - v) for u in _orbit(k, symmetry))
                   <= tol for k in kept):
            kept.append(v)
    w = bif.curve.dsigma
    return [v / np.sqrt(np.sum(w * v * v)) for v in kept]
