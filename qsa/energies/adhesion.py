"""The adhesion-repulsion two-point kernel and its discrete fields (kernel level).

The two-point energy of the paper (e:AdhE) is ::

    E_A = int_S int_S A(|d(s, s~)|^2) dsigma_s dsigma_s~,   d = gamma(s) - gamma(s~),

with the Lennard-Jones type kernel (e:LJ) ::

    A(l) = A0 (1 - l / (a^2 l*^2)) exp(-l / l*^2),   l = |d|^2.

Its L^2(dsigma) extrinsic gradient is (A.n + kappa B, 0) (e:Adh-Ex_grad) with the
two-point force and the surface density ::

    A(s) = 4 int A'(|d|^2) d dsigma_s~,     B(s) = 2 int A(|d|^2) dsigma_s~,

so the normal velocity is V^n_A = -(A.n + kappa B) (e:Adh-NV).

This module holds the *node-level* pieces: the kernel and its derivatives, the
neighbour lists (all pairs closer than a cutoff beyond which the kernel is
below ``rel * A0``), the discrete energy with node quadrature weights ``w``
(trapezoid rule on the periodic grid: ``w_j = g_j / N``, ``= L / N`` at scaled
arc length), the fields ``B`` and ``A`` (called ``force`` in code) and their
derivatives with respect to the node positions. Everything is vectorised over
pairs; with a neighbour list the cost is O(N + number of pairs).

The discrete energy (the quadrature of the paper's code, trapezoid in both
variables, the diagonal ``i = j`` included) is ::

    E_A = sum_i sum_j A(|X_i - X_j|^2) w_i w_j,

and the fields are exactly its partial derivatives:
``dE_A / dX_i = w_i force_i`` and ``B_i = 2 sum_j A(l_ij) w_j``.

Notes
-----
Conventions and errata, section 3 (kernel and its derivative) and section 6 (rigid-invariance
identities). The printed closed forms for the near-contact force and ``B(0)``
are off by factors 8 and 4 (Conventions and errata, section 6); nothing here uses them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.optimize import brentq
from scipy.spatial import cKDTree

from qsa._checks import real_number
from qsa.energies.adhesion_hessian import (
    AdhesionDerivatives,
    adhesion_derivatives,
    adjoint_fields,
)
from qsa.energies.adhesion_interp import coarse_rank, interpolated_hessian
from qsa.energies.adhesion_velocity import VelocityJacobian, adhesion_velocity_jacobian
from qsa.energies.base import Energy

__all__ = [
    "AdhesionKernel",
    "pair_list",
    "dense_pairs",
    "adhesion_pairs",
    "adhesion_energy",
    "adhesion_fields",
    "adhesion_normal_velocity",
    "uniform_weight_fields",
    "PairDerivatives",
    "adhesion_pair_derivatives",
    "adhesion_field_jacobians",
    "Adhesion",
]


@dataclass(frozen=True)
class AdhesionKernel:
    """Adhesion-repulsion kernel ``A(l) = A0 (1 - l/(a^2 l*^2)) exp(-l/l*^2)`` (e:LJ).

    Parameters
    ----------
    A0 : float
        Strength, ``A(0) = A0 > 0``.
    l_star : float
        Screening length ``l* > 0``.
    a : float
        Shape parameter ``a > 0``: ``A < 0`` for ``|d| > a l*``; the minimum is
        at ``|d| = l* sqrt(1 + a^2)`` with value ``-A0 a^-2 exp(-1 - a^2)``.

    Notes
    -----
    The argument ``l`` is the *squared* distance ``|d|^2``; ``dA`` and ``d2A``
    are derivatives with respect to ``l`` (Conventions and errata, section 3).

    Examples
    --------
    >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
    >>> float(k.A(0.0))
    10.0
    >>> bool(5.5 < k.cutoff_distance() / k.l_star < 7.5)
    True
    """

    A0: float
    l_star: float
    a: float

    def __post_init__(self):
        object.__setattr__(self, "A0", real_number(self.A0, "A0", positive=True))
        object.__setattr__(self, "l_star", real_number(self.l_star, "l_star", positive=True))
        object.__setattr__(self, "a", real_number(self.a, "a", positive=True))

    # ------------------------------------------------------------ the kernel
    def A(self, l):
        """Kernel value ``A(l)``, ``l = |d|^2`` (any shape).

        Parameters
        ----------
        l : array_like
            Squared distances.

        Returns
        -------
        ndarray, shape like ``l``

        Examples
        --------
        >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
        >>> float(k.A(0.25))  # zero at |d| = a l*
        0.0
        """
        s = self.l_star**2
        l = np.asarray(l, dtype=float)
        return self.A0 * (1.0 - l / (self.a**2 * s)) * np.exp(-l / s)

    def dA(self, l):
        """``A'(l) = A0 (l/(a^2 l*^4) - (1 + a^2)/(a^2 l*^2)) exp(-l/l*^2)``.

        Parameters
        ----------
        l : array_like
            Squared distances.

        Returns
        -------
        ndarray, shape like ``l``

        Examples
        --------
        >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
        >>> bool(abs(k.dA(k.minimum_distance**2)) < 1e-12)
        True
        """
        s = self.l_star**2
        c = self.a**2 * s
        l = np.asarray(l, dtype=float)
        return self.A0 * (l / (c * s) - 1.0 / c - 1.0 / s) * np.exp(-l / s)

    def d2A(self, l):
        """``A''(l) = A0 (2/(c s) + 1/s^2 - l/(c s^2)) exp(-l/s)``, ``s = l*^2, c = a^2 s``.

        Parameters
        ----------
        l : array_like
            Squared distances.

        Returns
        -------
        ndarray, shape like ``l``

        Examples
        --------
        >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
        >>> h = 1e-5
        >>> bool(abs((k.dA(0.3 + h) - k.dA(0.3 - h)) / (2 * h) - k.d2A(0.3)) < 1e-6)
        True
        """
        s = self.l_star**2
        c = self.a**2 * s
        l = np.asarray(l, dtype=float)
        return self.A0 * (2.0 / (c * s) + 1.0 / s**2 - l / (c * s**2)) * np.exp(-l / s)

    def __call__(self, l):
        return self.A(l)

    def derivatives(self, l, order=2):
        """``(A, A', A'')`` (``order=2``) or ``(A, A')`` (``order=1``) with one exponential.

        Parameters
        ----------
        l : array_like
            Squared distances.
        order : {1, 2}

        Returns
        -------
        tuple of ndarray, each shaped like ``l``

        Examples
        --------
        >>> import numpy as np
        >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
        >>> A, dA, d2A = k.derivatives(np.array([0.1, 0.4]))
        >>> bool(np.allclose(A, k.A(np.array([0.1, 0.4])))), len(k.derivatives(0.1, order=1))
        (True, 2)
        """
        s = self.l_star**2
        c = self.a**2 * s
        l = np.asarray(l, dtype=float)
        e = self.A0 * np.exp(-l / s)
        A = (1.0 - l / c) * e
        dA = (l / (c * s) - 1.0 / c - 1.0 / s) * e
        if order == 1:
            return A, dA
        return A, dA, (2.0 / (c * s) + 1.0 / s**2 - l / (c * s**2)) * e

    # --------------------------------------------------------------- scales
    @property
    def minimum_distance(self) -> float:
        """Distance ``l* sqrt(1 + a^2)`` at which ``A`` is minimal.

        Examples
        --------
        >>> round(AdhesionKernel(A0=1.0, l_star=1.0, a=1.0).minimum_distance ** 2, 12)
        2.0
        """
        return self.l_star * math.sqrt(1.0 + self.a**2)

    @property
    def pair_separation(self) -> float:
        """Optimal separation of two parallel strands, ``l* sqrt(a^2 + 1/2)``.

        Conventions and errata, section 6.

        Examples
        --------
        >>> round(AdhesionKernel(A0=1.0, l_star=2.0, a=1.0).pair_separation ** 2, 12)
        6.0
        """
        return self.l_star * math.sqrt(self.a**2 + 0.5)

    def cutoff_distance(self, rel=1e-16) -> float:
        """Distance beyond which ``|A| <= rel A0`` and ``|A'| <= rel A0``.

        Both bounds hold for every larger distance (the tails are monotone there).
        With ``rel = 1e-16`` this is about 6.3-7 ``l*`` (``A'`` carries a factor
        ``1/l*^2``, so small ``l*`` needs a slightly wider cutoff).

        Parameters
        ----------
        rel : float
            Relative threshold, ``0 < rel < 1``.

        Returns
        -------
        float
            The cutoff distance ``|d|`` (not squared).

        Examples
        --------
        >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
        >>> r = k.cutoff_distance(1e-8)
        >>> bool(abs(k.A(r**2)) <= 1e-8 * k.A0 and abs(k.A((0.9 * r) ** 2)) > 1e-8 * k.A0)
        True
        """
        rel = float(rel)
        if not (0.0 < rel < 1.0):
            raise ValueError(f"rel must lie in (0, 1), got {rel!r}")
        a2 = self.a**2
        s = self.l_star**2

        # u = l / l*^2; both |A|/A0 and |A'|/A0 are decreasing for u > 2 + a^2.
        def log_excess(u):
            fa = abs(1.0 - u / a2)
            fd = abs(u - 1.0 - a2) / (a2 * s)
            return math.log(max(fa, fd)) - u - math.log(rel)

        u0 = 2.0 + a2
        if log_excess(u0) <= 0.0:
            return self.l_star * math.sqrt(u0)
        u1 = 2.0 * u0
        while log_excess(u1) > 0.0:
            u1 *= 2.0
        u = brentq(log_excess, u0, u1, xtol=1e-12, rtol=1e-14)
        return self.l_star * math.sqrt(u)


# ---------------------------------------------------------------- pair lists
def _check_positions(x, y):
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape:
        raise ValueError(f"x and y must be 1-d of equal length, got {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("positions x, y contain NaN or inf")
    return x, y


def pair_list(x, y, cutoff):
    """All node pairs closer than ``cutoff`` (k-d tree), as index arrays with ``i < j``.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Node positions.
    cutoff : float
        Distance; pairs with ``|X_i - X_j| <= cutoff`` are returned.

    Returns
    -------
    i, j : ndarray of intp, shape (P,)
        Pair indices, ``i < j``, sorted lexicographically. Each unordered pair
        appears once; use both orientations for symmetric sums.

    Examples
    --------
    >>> i, j = pair_list([0, 1, 2, 3, 10], [0, 0, 0, 0, 0], 1.5)
    >>> i.tolist(), j.tolist()
    ([0, 1, 2], [1, 2, 3])
    """
    x, y = _check_positions(x, y)
    cutoff = real_number(cutoff, "cutoff", positive=True)
    if x.size > 1:
        diameter = np.hypot(np.ptp(x), np.ptp(y))
        if diameter < cutoff:
            return dense_pairs(x.size)  # every pair is within the cutoff (long-range kernel)
        if cutoff > 0.25 * diameter and x.size <= 4000:
            # a large share of all pairs is within reach: filtering them is cheaper than a tree
            i, j = dense_pairs(x.size)
            keep = (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 <= cutoff * cutoff
            return i[keep], j[keep]
    tree = cKDTree(np.column_stack([x, y]))
    pairs = tree.query_pairs(cutoff, output_type="ndarray")
    if pairs.size == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty.copy()
    i = np.minimum(pairs[:, 0], pairs[:, 1]).astype(np.intp)
    j = np.maximum(pairs[:, 0], pairs[:, 1]).astype(np.intp)
    # one int64 key per (unique) pair; the tree's output comes in long sorted runs, which
    # the stable sort (timsort) merges ~10x faster than lexsort
    order = np.argsort(i.astype(np.int64) * x.size + j, kind="stable")
    return i[order], j[order]


def dense_pairs(N):
    """All pairs ``i < j`` of ``N`` nodes (the exact path, ``N (N-1)/2`` pairs).

    The arrays are cached per ``N`` and read-only (they depend on ``N`` alone).

    Parameters
    ----------
    N : int

    Returns
    -------
    i, j : ndarray of intp, shape (N (N - 1) / 2,)

    Examples
    --------
    >>> i, j = dense_pairs(3)
    >>> i.tolist(), j.tolist()
    ([0, 0, 1], [1, 2, 2])
    """
    return _dense_pairs(int(N))


@functools.lru_cache(maxsize=8)
def _dense_pairs(N):
    i, j = np.triu_indices(N, k=1)
    i = i.astype(np.intp)
    j = j.astype(np.intp)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


class _LastCall:
    """The values computed for the last ``size`` keys asked for (memory stays bounded).

    The analysis of one curve asks for the same pair list, fields and derivatives several
    times, each a pass over all pairs; the key holds the exact bytes of every input, so a
    hit returns what the computation would return.
    """

    def __init__(self, size=1):
        self._size = int(size)
        self._entries: list = []  # (key, value), most recent first

    def get(self, key, compute):
        for k, (old, value) in enumerate(self._entries):
            if old == key:
                self._entries.insert(0, self._entries.pop(k))
                return value
        value = compute()
        self._entries.insert(0, (key, value))
        del self._entries[self._size:]
        return value


# The neighbour list at the last positions asked for: the energy's fields and its
# derivatives at one curve each need it (a k-d tree query, ~0.5 s at 4M pairs).
_LAST_PAIRS = _LastCall()


# pairs per chunk of the field sums (their temporaries stay in cache)
_PAIR_CHUNK = 1 << 16

# Neighbour lists with at least this many pairs make the spectral solvers' Hessian
# (Adhesion.factored_hessian) panel-interpolated when that is of lower rank than N
# (told by coarse_rank before any build): a long-range kernel's few panels (l* = 0.5,
# N = 1000-1200: rank ~1000) make the coarse route (qsa.spectra.coarse) 1.5-4 times
# faster than the assembled blocks
INTERPOLATE_PAIRS = 500_000
# and from this many on whatever its rank: the assembled blocks take ~0.8 kB per pair
# (~2.4 GB here), and the coarse route is as fast at ~2.7M pairs (folded CHA state,
# N = 3600, rank 2N), 1.7 times faster at 4.9M (N = 4800)
ASSEMBLED_PAIRS_LIMIT = 3_000_000

# Neighbour lists taken with a slightly wider reach, at the last few positions: a curve
# that moved by less than the margin (the perturbed copies of a residual-floor estimate,
# a small Newton step) gets its exact list by filtering one of them, in the same sorted
# order as a fresh query, instead of a new k-d tree query (~3 s at 18M pairs).
_MARGIN = 1e-3
_SUPERSETS: list = []
_KEEP_SUPERSETS = 2


def _near_pairs(x, y, cutoff):
    """:func:`pair_list` ``(x, y, cutoff)``, by filtering a kept wider list when one covers it."""
    for k, sup in enumerate(_SUPERSETS):
        if sup["cutoff"] == cutoff and sup["x"].shape == x.shape:
            moved = max(np.max(np.abs(x - sup["x"])), np.max(np.abs(y - sup["y"])), 0.0)
            # a pair's distance changes by at most 2 sqrt(2) max|moved coordinate|
            if 2.0 * np.sqrt(2.0) * moved < sup["reach"] - cutoff:
                _SUPERSETS.insert(0, _SUPERSETS.pop(k))
                return _within(x, y, sup["i"], sup["j"], cutoff)
    reach = cutoff * (1.0 + _MARGIN)
    i, j = pair_list(x, y, reach)
    small = np.int32 if x.size < 2**31 else np.intp
    _SUPERSETS.insert(0, {"cutoff": cutoff, "reach": reach, "x": x.copy(), "y": y.copy(),
                          "i": i.astype(small), "j": j.astype(small)})
    del _SUPERSETS[_KEEP_SUPERSETS:]
    return _within(x, y, i, j, cutoff)


def _within(x, y, i, j, cutoff, chunk=1 << 22):
    """The pairs of ``(i, j)`` (sorted) with ``|X_i - X_j| <= cutoff``, as ``intp`` arrays."""
    keep = np.empty(i.size, dtype=bool)
    c2 = cutoff * cutoff
    for start in range(0, i.size, chunk):
        a, b = i[start:start + chunk], j[start:start + chunk]
        keep[start:start + chunk] = (x[a] - x[b]) ** 2 + (y[a] - y[b]) ** 2 <= c2
    return i[keep].astype(np.intp), j[keep].astype(np.intp)


def _cached_pairs(kernel, x, y, rel=1e-16):
    """The neighbour list of :func:`adhesion_pairs` as kept (shared: read, never modify)."""
    cutoff = kernel.cutoff_distance(rel)
    xa, ya = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    key = (cutoff, xa.tobytes(), ya.tobytes())
    return _LAST_PAIRS.get(key, lambda: _near_pairs(xa, ya, cutoff))


def adhesion_pairs(kernel, x, y, *, method="neighbours", rel=1e-16):
    """Pairs entering the adhesion sums: a cutoff neighbour list or all pairs.

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
    method : {"neighbours", "dense"}
        ``"neighbours"``: pairs within ``kernel.cutoff_distance(rel)``;
        ``"dense"``: every pair (exact, O(N^2)).
    rel : float
        Cutoff threshold passed to :meth:`AdhesionKernel.cutoff_distance`.

    Returns
    -------
    i, j : ndarray of intp, shape (P,)
        Pairs with ``i < j``.

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=1.0, l_star=0.05, a=1.0)
    >>> t = 2 * np.pi * np.arange(200) / 200
    >>> near = adhesion_pairs(k, np.cos(t), np.sin(t))
    >>> every = adhesion_pairs(k, np.cos(t), np.sin(t), method="dense")
    >>> near[0].size < every[0].size == 200 * 199 // 2
    True
    """
    if method == "neighbours":
        hit = _cached_pairs(kernel, x, y, rel)
        return hit[0].copy(), hit[1].copy()
    if method == "dense":
        x, _ = _check_positions(x, y)
        return dense_pairs(x.size)
    raise ValueError(f"method must be 'neighbours' or 'dense', got {method!r}")


def _weights(w, N):
    w = np.asarray(w, dtype=float)
    if w.ndim == 0:
        w = np.full(N, float(w))
    if w.shape != (N,):
        raise ValueError(f"w must be a scalar or have shape ({N},), got {w.shape}")
    return w


def _resolve_pairs(kernel, x, y, pairs, method):
    if pairs is None:
        return adhesion_pairs(kernel, x, y, method=method)
    i, j = pairs
    return np.asarray(i, dtype=np.intp), np.asarray(j, dtype=np.intp)


# ------------------------------------------------------------ energy, fields
def adhesion_energy(kernel, x, y, w, *, pairs=None, method="neighbours"):
    """Discrete two-point energy ``E_A = sum_i sum_j A(|X_i - X_j|^2) w_i w_j`` (e:AdhE).

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
        Node positions.
    w : float or array_like, shape (N,)
        Node quadrature weights of dsigma (``L / N`` at scaled arc length).
    pairs : tuple of ndarray, optional
        ``(i, j)`` with ``i < j`` from :func:`pair_list` / :func:`dense_pairs`
        computed by ``method`` when omitted.
    method : {"neighbours", "dense"}

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=2.0, l_star=0.5, a=1.0)
    >>> adhesion_energy(k, [0.0, 0.5], [0.0, 0.0], 1.0)  # 2 A0 + 2 A(0.25) = 4 + 0
    4.0
    >>> t = 2 * np.pi * np.arange(64) / 64
    >>> args = (k, np.cos(t), np.sin(t), 2 * np.pi / 64)
    >>> bool(np.isclose(adhesion_energy(*args), adhesion_energy(*args, method="dense")))
    True
    """
    x, y = _check_positions(x, y)
    w = _weights(w, x.size)
    i, j = _resolve_pairs(kernel, x, y, pairs, method)
    l = (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2
    return float(kernel.A0 * np.sum(w * w) + 2.0 * np.sum(kernel.A(l) * w[i] * w[j]))


def adhesion_fields(kernel, x, y, w, *, pairs=None, method="neighbours"):
    """The fields ``B`` and ``force`` (the paper's 𝔸) at the nodes.

    ``B_i = 2 sum_j A(l_ij) w_j`` and ``force_i = 4 sum_j A'(l_ij) (X_i - X_j) w_j``,
    ``l_ij = |X_i - X_j|^2`` (trapezoid quadrature of e:Adh-NV's integrals, the
    diagonal included: it adds ``2 A0 w_i`` to ``B_i`` and nothing to the force).

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
    w : float or array_like, shape (N,)
        Node quadrature weights of dsigma.
    pairs, method
        As in :func:`adhesion_energy`.

    Returns
    -------
    B : ndarray, shape (N,)
    force : ndarray, shape (N, 2)
        The two-point force 𝔸; ``dE_A/dX_i = w_i force_i``. The adhesion normal
        velocity is ``-(force . n + kappa B)`` (e:Adh-NV).

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
    >>> t = 2 * np.pi * np.arange(64) / 64
    >>> x, y = np.cos(t), np.sin(t)
    >>> B, force = adhesion_fields(k, x, y, 2 * np.pi / 64)
    >>> bool(np.ptp(B) < 1e-10), bool(np.allclose(force[:, 0] * y - force[:, 1] * x, 0))
    (True, True)
    >>> X = np.concatenate([x, y]); e = np.zeros(128); e[0] = 1e-6
    >>> E = lambda X: adhesion_energy(k, X[:64], X[64:], 2 * np.pi / 64)
    >>> fd = (E(X + e) - E(X - e)) / 2e-6
    >>> bool(np.isclose(fd, 2 * np.pi / 64 * force[0, 0], rtol=1e-6))  # dE/dx_0 = w_0 F_0
    True
    """
    x, y = _check_positions(x, y)
    N = x.size
    w = _weights(w, N)
    i, j = _resolve_pairs(kernel, x, y, pairs, method)
    if np.all(w == w[0]):  # uniform weights (scaled arc length): fewer gathers
        return uniform_weight_fields(kernel, x, y, w[0], i, j)
    sA, sx, sy = np.zeros(N), np.zeros(N), np.zeros(N)
    for start in range(0, i.size, _PAIR_CHUNK):
        a, b = i[start:start + _PAIR_CHUNK], j[start:start + _PAIR_CHUNK]
        dx = x[a] - x[b]
        dy = y[a] - y[b]
        Av, dAv = kernel.derivatives(dx * dx + dy * dy, order=1)
        sA += np.bincount(a, Av * w[b], N) + np.bincount(b, Av * w[a], N)
        sx += np.bincount(a, dAv * dx * w[b], N) - np.bincount(b, dAv * dx * w[a], N)
        sy += np.bincount(a, dAv * dy * w[b], N) - np.bincount(b, dAv * dy * w[a], N)
    B = 2.0 * kernel.A0 * w + 2.0 * sA
    return B, np.column_stack([4.0 * sx, 4.0 * sy])


def uniform_weight_fields(kernel, x, y, w, i, j):
    """``(B, force)`` of :func:`adhesion_fields` for one scalar weight ``w`` (no input checks).

    The inner loop of the flow models: ``x, y`` must be finite float arrays of
    shape (N,) and ``(i, j)`` a pair list with ``i < j``.

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : ndarray, shape (N,)
    w : float
    i, j : ndarray of intp, shape (P,)

    Returns
    -------
    B : ndarray, shape (N,)
    force : ndarray, shape (N, 2)

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=10.0, l_star=0.3, a=1.0)
    >>> t = 2 * np.pi * np.arange(32) / 32
    >>> x, y = np.cos(t), 0.5 * np.sin(t)
    >>> i, j = dense_pairs(32)
    >>> B, F = uniform_weight_fields(k, x, y, 0.1, i, j)
    >>> B2, F2 = adhesion_fields(k, x, y, 0.1, method="dense")
    >>> bool(np.allclose(B, B2)), bool(np.allclose(F, F2))
    (True, True)
    """
    N = x.size
    sA, sx, sy = np.zeros(N), np.zeros(N), np.zeros(N)
    for start in range(0, i.size, _PAIR_CHUNK):  # chunks stay in cache: ~5x faster at 20M
        a, b = i[start:start + _PAIR_CHUNK], j[start:start + _PAIR_CHUNK]
        dx = x[a] - x[b]
        dy = y[a] - y[b]
        Av, dAv = kernel.derivatives(dx * dx + dy * dy, order=1)
        sA += np.bincount(a, Av, N) + np.bincount(b, Av, N)
        gx = dAv * dx
        gy = dAv * dy
        sx += np.bincount(a, gx, N) - np.bincount(b, gx, N)
        sy += np.bincount(a, gy, N) - np.bincount(b, gy, N)
    B = 2.0 * w * (kernel.A0 + sA)
    force = np.empty((N, 2))
    force[:, 0] = 4.0 * w * sx
    force[:, 1] = 4.0 * w * sy
    return B, force


def adhesion_normal_velocity(kernel, x, y, nx, ny, kappa, w, *, pairs=None,
                             method="neighbours"):
    """Two-point normal velocity ``V^n_A = -(force.n + kappa B)`` (e:Adh-NV).

    ``(force . n + kappa B, 0)`` is the extrinsic L^2(dsigma) gradient
    (e:Adh-Ex_grad); rigid invariance makes it orthogonal to the rigid normal
    velocities ``e_k . n`` and ``gamma . tau`` in ``<f, h> = int f h dsigma``
    (Conventions and errata, section 6).

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
        Node positions.
    nx, ny : array_like, shape (N,)
        Outward unit normal at the nodes.
    kappa : array_like, shape (N,)
        Curvature (``+1/R`` on a counter-clockwise circle).
    w : float or array_like, shape (N,)
        Node weights of dsigma (``g_j / N``).
    pairs, method
        As in :func:`adhesion_energy`.

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    >>> (x, y), (nx, ny) = c.positions(), c.normal()
    >>> k = AdhesionKernel(A0=10.0, l_star=0.3, a=1.0)
    >>> V = adhesion_normal_velocity(k, x, y, nx, ny, c.kappa, c.dsigma)
    >>> bool(abs(V @ (nx * c.dsigma)) < 1e-8 * np.abs(V).max())  # orthogonal to e1 . n
    True
    """
    B, F = adhesion_fields(kernel, x, y, w, pairs=pairs, method=method)
    return -(F[:, 0] * np.asarray(nx) + F[:, 1] * np.asarray(ny) + np.asarray(kappa) * B)


class PairDerivatives(NamedTuple):
    """Per unordered pair ``(i, j)``, ``i < j``: ``d = X_i - X_j``, ``A'(|d|^2)`` and
    the symmetric 2x2 matrix ``H = 2 A''(|d|^2) d d^T + A'(|d|^2) I``.

    Parameters
    ----------
    i, j : ndarray of intp, shape (P,)
    dx, dy : ndarray, shape (P,)
        Components of ``d``.
    dA : ndarray, shape (P,)
    hxx, hxy, hyy : ndarray, shape (P,)
        Entries of ``H``.

    Examples
    --------
    >>> t = adhesion_pair_derivatives(AdhesionKernel(1.0, 1.0, 1.0), [0.0, 1.0], [0.0, 0.0])
    >>> t.i.tolist(), t.dx.tolist(), bool(t.hxy[0] == 0)
    ([0], [-1.0], True)
    """

    i: np.ndarray
    j: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dA: np.ndarray
    hxx: np.ndarray
    hxy: np.ndarray
    hyy: np.ndarray


def adhesion_pair_derivatives(kernel, x, y, *, pairs=None, method="neighbours"):
    """Pair terms of the derivatives of ``B`` and ``force`` with respect to positions.

    For a directed pair ``(p, q)``, ``p != q``, ``d = X_p - X_q``, ``l = |d|^2``
    and weights held fixed: ::

        dB_p/dX_q     = -4 w_q A'(l) d,
        dforce_p/dX_q = -4 w_q H,     H = 2 A''(l) d d^T + A'(l) I,

    and the diagonal blocks are ``dB_p/dX_p = force_p``,
    ``dforce_p/dX_p = 4 sum_q w_q H_pq`` (translation invariance). ``H`` is
    the same for both orientations of a pair, ``d`` changes sign; so the terms
    are returned once per unordered pair (O(P) memory, no 2x2xP arrays).

    Returns
    -------
    PairDerivatives
        Fields ``i, j, dx, dy, dA, hxx, hxy, hyy``, each shape (P,).

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=10.0, l_star=0.5, a=1.0)
    >>> t = adhesion_pair_derivatives(k, [0.0, 0.3, 0.0], [0.0, 0.0, 0.4], method="dense")
    >>> bool(np.allclose(t.dA, k.dA(t.dx**2 + t.dy**2))), t.i.size
    (True, 3)

    See Also
    --------
    adhesion_field_jacobians : the assembled sparse matrices.
    """
    x, y = _check_positions(x, y)
    i, j = _resolve_pairs(kernel, x, y, pairs, method)
    dx = x[i] - x[j]
    dy = y[i] - y[j]
    l = dx * dx + dy * dy
    _, dAv, d2Av = kernel.derivatives(l)
    t = 2.0 * d2Av
    return PairDerivatives(i, j, dx, dy, dAv, t * dx * dx + dAv, t * dx * dy, t * dy * dy + dAv)


def adhesion_field_jacobians(kernel, x, y, w, *, pairs=None, method="neighbours"):
    """Sparse Jacobians of ``B`` and ``force`` with respect to the positions (fixed ``w``).

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
    w : float or array_like, shape (N,)
    pairs, method
        As in :func:`adhesion_energy`.

    Returns
    -------
    JB : scipy.sparse.csr_matrix, shape (N, 2N)
        ``dB_p / d(x, y)``; columns ordered ``[x_0..x_{N-1}, y_0..y_{N-1}]``.
    JF : scipy.sparse.csr_matrix, shape (2N, 2N)
        ``d(force_x, force_y) / d(x, y)``, rows ``[force_x; force_y]``.

    Examples
    --------
    >>> import numpy as np
    >>> k = AdhesionKernel(A0=10.0, l_star=0.3, a=1.0)
    >>> t = 2 * np.pi * np.arange(32) / 32
    >>> X = np.concatenate([np.cos(t), 0.5 * np.sin(t)])
    >>> JB, JF = adhesion_field_jacobians(k, X[:32], X[32:], 0.1, method="dense")
    >>> V = np.sin(3 * np.arange(64)); h = 1e-6
    >>> B = lambda X: adhesion_fields(k, X[:32], X[32:], 0.1, method="dense")[0]
    >>> bool(np.allclose((B(X + h * V) - B(X - h * V)) / (2 * h), JB @ V, atol=1e-6))
    True
    """
    x, y = _check_positions(x, y)
    N = x.size
    w = _weights(w, N)
    t = adhesion_pair_derivatives(kernel, x, y, pairs=pairs, method=method)
    B, F = adhesion_fields(kernel, x, y, w, pairs=(t.i, t.j))
    p = np.concatenate([t.i, t.j])
    q = np.concatenate([t.j, t.i])
    sgn = np.concatenate([np.ones(t.i.size), -np.ones(t.i.size)])
    wq = -4.0 * w[q]
    d = (np.concatenate([t.dx, t.dx]) * sgn, np.concatenate([t.dy, t.dy]) * sgn)
    H = {(0, 0): np.tile(t.hxx, 2), (0, 1): np.tile(t.hxy, 2), (1, 1): np.tile(t.hyy, 2)}
    H[(1, 0)] = H[(0, 1)]
    n = np.arange(N)
    rows, cols, vals = [], [], []
    for b in range(2):
        rows += [p, n]
        cols += [b * N + q, b * N + n]
        vals += [wq * np.tile(t.dA, 2) * d[b], F[:, b]]
    JB = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(N, 2 * N))
    rows, cols, vals = [], [], []
    for a in range(2):
        for b in range(2):
            v = wq * H[(a, b)]
            rows += [a * N + p, a * N + n]
            cols += [b * N + q, b * N + n]
            vals += [v, -np.bincount(p, v, N)]
    JF = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(2 * N, 2 * N))
    return JB, JF


# --------------------------------------------------------- Curve-level energy
# The derivatives at the last curve asked for: an analysis asks for the gradient, the
# Hessian and Hessian-vector products at one curve several times, and each set costs a
# pass over all pairs. One entry, keyed by the kernel and the curve's arrays.
_LAST_DERIVATIVES = _LastCall()
# Likewise the fields (B, force), O(N) each, at the last four curves: a curve's residual,
# multipliers, residual scale and floor (at scaled and perturbed copies) and its kernel
# report each ask for them.
_LAST_FIELDS = _LastCall(size=4)


@dataclass(frozen=True)
class Adhesion(Energy):
    """Two-point adhesion-repulsion energy of a :class:`~qsa.curve.Curve` (e:AdhE, e:LJ).

    Parameters
    ----------
    A0 : float
        Kernel height (repulsion at contact), ``> 0``.
    l_star : float
        Screening length, ``> 0``.
    a : float
        Shape parameter: ``A`` changes sign at ``|d| = a l_star``; paired sheets
        settle at the separation ``l_star sqrt(a^2 + 1/2)`` (Conventions and errata, section 6).
    method : {"neighbours", "dense"}
        Cutoff neighbour list (O(N) for a short-range kernel) or all pairs.

    Notes
    -----
    The node quadrature is ``dsigma_j = g_j / N`` in both integrals, diagonal
    included. Provided: ``energy``, ``fields`` (B and the force 𝔸),
    ``extrinsic_gradient`` ``(𝔸.n + kappa B, 0)`` (e:Adh-Ex_grad),
    ``normal_velocity`` ``-(𝔸.n + kappa B)`` (e:Adh-NV), and the exact derivatives
    of the discrete energy as a function of ``U = (kappa, g)`` (positions
    ``gamma0 + D tau``, base point and angle fixed; :mod:`qsa.energies.adhesion_hessian`):
    ``gradient`` (an intrinsic gradient of e:Adh-In_grad, ``M-dagger nabla_I E =
    (𝔸.n + kappa B, 0)``), ``hessian`` (dense, or factored on finite-difference
    grids) and ``hessian_vector``, all O(N + pairs) except the dense Hessian.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> E = Adhesion(A0=10.0, l_star=0.5, a=1.0)
    >>> c = Curve.circle(1.0, Fourier(65))
    >>> V = E.normal_velocity(c)          # constant on a circle
    >>> bool(np.ptp(V) < 1e-10 * np.abs(V).max())
    True
    """

    A0: float
    l_star: float
    a: float = 1.0
    method: str = "neighbours"
    kernel: AdhesionKernel = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.method not in ("neighbours", "dense"):
            raise ValueError(f"method must be 'neighbours' or 'dense', got {self.method!r}")
        kernel = AdhesionKernel(self.A0, self.l_star, self.a)
        for name in ("A0", "l_star", "a"):
            object.__setattr__(self, name, getattr(kernel, name))
        object.__setattr__(self, "kernel", kernel)

    def __repr__(self):
        return f"Adhesion(A0={self.A0}, l_star={self.l_star}, a={self.a})"

    def _data(self, c):
        x, y = c.positions()
        return x, y, c.dsigma

    def energy(self, c) -> float:
        """Discrete ``E_A`` with ``w = dsigma`` (:func:`adhesion_energy`), a float."""
        x, y, w = self._data(c)
        return adhesion_energy(self.kernel, x, y, w, method=self.method)

    def fields(self, c):
        """``(B, force)``: B shape (N,), the force 𝔸 shape (N, 2).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        B : ndarray, shape (N,)
        force : ndarray, shape (N, 2)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> B, force = Adhesion(10.0, 0.5).fields(Curve.circle(1.0, Fourier(33)))
        >>> B.shape, force.shape, bool(np.ptp(B) < 1e-10)
        ((33,), (33, 2), True)
        """
        x, y, w = self._data(c)
        key = (self.kernel, self.method, x.tobytes(), y.tobytes(), np.asarray(w).tobytes())
        hit = _LAST_FIELDS.get(key, lambda: adhesion_fields(self.kernel, x, y, w,
                                                            method=self.method))
        return hit[0].copy(), hit[1].copy()

    def extrinsic_gradient(self, c) -> np.ndarray:
        """``(𝔸.n + kappa B, 0)``, gradient in ``<f, h> = int f h dsigma`` (e:Adh-Ex_grad).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)
            Stacked ``[normal, tangential]`` components; the tangential one is 0.
        """
        B, force = self.fields(c)
        n = c.normal()
        return np.concatenate([force[:, 0] * n[0] + force[:, 1] * n[1] + c.kappa * B,
                               np.zeros(c.N)])

    def normal_velocity(self, c) -> np.ndarray:
        """``V^n_A = -(𝔸.n + kappa B)`` (e:Adh-NV).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (N,)
        """
        return -self.extrinsic_gradient(c)[: c.N]

    def derivatives(self, c) -> AdhesionDerivatives:
        """Pair data and adjoint fields of the exact derivatives at ``c`` (reuse them).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        AdhesionDerivatives
            ``.gradient()``, ``.hessian(form)``, ``.hessian_vector(v)``.
        """
        x, y = c.positions()
        key = (self.kernel, self.method, type(c.grid).__name__, c.N, x.tobytes(), y.tobytes(),
               np.asarray(c.kappa).tobytes(), np.asarray(c.g).tobytes())
        return _LAST_DERIVATIVES.get(key, lambda: adhesion_derivatives(
            self.kernel, c, adhesion_pairs(self.kernel, x, y, method=self.method)))

    def gradient(self, c) -> np.ndarray:
        """``nabla_I E_A`` in ``<f, h> = int f h dsigma``: the discrete energy's exact derivative.

        ``d/d delta E_A(U + delta U1) = <nabla_I E_A, U1>`` for every ``U1`` (O(N + pairs)).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier, geometry
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(129))
        >>> E = Adhesion(10.0, 0.5)
        >>> back = geometry.M_adjoint(c) @ E.gradient(c)   # e:Adh-In_grad, spectrally
        >>> bool(np.allclose(back, E.extrinsic_gradient(c), atol=1e-6))
        True
        """
        # from the fields alone (the second-derivative data of derivatives() is not needed)
        B, force = self.fields(c)
        _, a, _, beta = adjoint_fields(c, c.dsigma[:, None] * force)
        ds = c.dsigma
        return (np.concatenate([c.g * beta, a + c.kappa * beta + c.grid.weights * B])
                / np.concatenate([ds, ds]))

    def hessian(self, c, form="auto"):
        """``nabla_I^2 E_A`` in ``<f, h> = int f h dsigma``: exact, dsigma-self-adjoint.

        Parameters
        ----------
        c : Curve
        form : {"auto", "dense", "reduced"}
            See :meth:`AdhesionDerivatives.hessian
            <qsa.energies.adhesion_hessian.AdhesionDerivatives.hessian>`: a
            :class:`~qsa.linalg.ReducedHessian` (finite differences, short range) or a
            dense ndarray.

        Returns
        -------
        ndarray or ReducedHessian, shape (2N, 2N)
        """
        return self.derivatives(c).hessian(form)

    def factored_hessian(self, c):
        """``nabla_I^2 E_A`` for the spectral solvers: :meth:`hessian`, or on finite-difference
        grids with many interacting pairs the panel-interpolated form.

        With at least ``INTERPOLATE_PAIRS`` pairs in the neighbour list and a rank ``3M``
        below ``N`` (:func:`~qsa.energies.adhesion_interp.coarse_rank`, told before any
        build), or with ``ASSEMBLED_PAIRS_LIMIT`` pairs or more whatever the rank, the
        pair Hessian is compressed by
        :func:`~qsa.energies.adhesion_interp.interpolated_pair_hessian` (storage
        O(N + M^2) instead of ~0.8 kB per pair) and returned as the extended-state
        :func:`~qsa.energies.adhesion_interp.interpolated_reduced_hessian`. That matrix
        carries the compression's error estimate
        (:meth:`~qsa.linalg.ReducedHessian.approximation_error`), which the spectra add
        to their eigenvalues' error estimates. Otherwise the exact reduced (or dense) form.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray or ReducedHessian, shape (2N, 2N)
        """
        if c.grid.sparse and self.method == "neighbours":
            x, y = c.positions()
            P = _cached_pairs(self.kernel, x, y)[0].size
            if P >= ASSEMBLED_PAIRS_LIMIT or (P >= INTERPOLATE_PAIRS
                                              and coarse_rank(self.kernel, c) < c.N):
                H = interpolated_hessian(self.kernel, c, max_rank=(
                    None if P < ASSEMBLED_PAIRS_LIMIT else 1 << 62))
                if H is not None:
                    return H
        return self.hessian(c)

    def hessian_vector(self, c, v) -> np.ndarray:
        """``nabla_I^2 E_A v`` without assembling the Hessian (O(N + pairs) per vector).

        Parameters
        ----------
        c : Curve
        v : array_like, shape (2N,) or (2N, m)

        Returns
        -------
        ndarray, shape like ``v``
        """
        return self.derivatives(c).hessian_vector(v)

    def normal_velocity_jacobian(self, c) -> VelocityJacobian:
        """The exact derivative of :meth:`normal_velocity` with respect to ``U = (kappa, g)``.

        Base point and angle fixed, pairs held fixed (:mod:`qsa.energies.adhesion_velocity`).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        VelocityJacobian
            ``J @ U1`` (O(N + pairs)), ``J.dense()`` (N, 2N), and the sparse parts
            ``VU``, ``VY`` for a Newton matrix with the positions as extra unknowns.
        """
        x, y = c.positions()
        return adhesion_velocity_jacobian(self.kernel, c,
                                          adhesion_pairs(self.kernel, x, y, method=self.method))
