"""Memory a command will need, estimated before it allocates, against what is available.

A run that does not fit is refused at once with the estimate and the limit
(exit code 2) instead of a memory traceback or a crash in the sparse LU after
minutes of work. Each kind of run has a :class:`Footprint`, a fit of its peak
resident memory (RSS) measured at moderate N (``benchmarks/bench_memory.py``
measures it again and prints measured against estimated)::

    peak RSS ~ base + per_node N + per_node2 N^2 + per_pair P

with P the number of node pairs the adhesion kernel couples (CHA flows). The
estimate is the fit times :data:`MARGIN`; dense Fourier operators make the
equilibria and spectra quadratic in N, the sparse finite-difference DAE of
the flows linear. Measured (peak RSS, one BLAS thread) the estimates are
1.05-1.6 times the peak: e.g. a faceting flow at N = 128000 peaks at 2.0 GiB
(estimate 2.6 GiB), a Fourier spectrum at N = 1201 at 1.25 GiB (1.5 GiB), a CHA
flow with all pairs coupled at N = 4000 at 4.3 GiB (6.8 GiB). Polishing on a
finite-difference grid is the least regular: the fill of the sparse LU of its
bordered Newton matrix depends on the ordering, from 2 kB to 85 kB per node at
the measured N; the estimate takes the largest.

The limit is the kernel's ``MemAvailable`` (``/proc/meminfo``; elsewhere the
free physical pages, ``os.sysconf``), or the environment variable
``QSA_MEMORY_LIMIT`` (bytes, or with a suffix ``K``, ``M``, ``G``) when set.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

__all__ = ["Footprint", "FOOTPRINTS", "MARGIN", "available_bytes", "require", "flow_bytes",
           "equilibrium_bytes", "polish_bytes", "spectrum_bytes", "format_bytes"]

#: Safety factor on the fitted peak (the fits are within ~15% at the measured N).
MARGIN = 1.25


@dataclass(frozen=True)
class Footprint:
    """Fitted peak resident memory of one kind of run, in bytes.

    Attributes
    ----------
    base : float
        The interpreter with numpy/scipy and qsa loaded, plus constant work arrays.
    per_node, per_node2 : float
        Bytes per node and per node squared (dense ``N x N`` operators).
    per_pair : float
        Bytes per coupled node pair (adhesion).
    """

    base: float
    per_node: float = 0.0
    per_node2: float = 0.0
    per_pair: float = 0.0

    def peak(self, N, pairs=0.0) -> float:
        """The fitted peak RSS at ``N`` nodes (and ``pairs`` coupled pairs)."""
        return self.base + self.per_node * N + self.per_node2 * N * N + self.per_pair * pairs

    def largest_N(self, limit, pairs_per_N2=0.0) -> int:
        """The largest N whose estimate (with :data:`MARGIN`) stays within ``limit`` bytes."""
        a = self.per_node2 + self.per_pair * pairs_per_N2
        b, c = self.per_node, self.base - limit / MARGIN
        if c >= 0:
            return 0
        if a == 0:
            return int(-c / b) if b > 0 else 10**12
        return int((-b + math.sqrt(b * b - 4 * a * c)) / (2 * a))


_MB = 2.0**20
#: The fits (see the module docstring; ``benchmarks/bench_memory.py`` measures them).
FOOTPRINTS = {
    "flow-facet": Footprint(base=150 * _MB, per_node=16e3),
    "flow-cha": Footprint(base=150 * _MB, per_node=16e3, per_pair=700.0),
    "equilibrium-fourier": Footprint(base=90 * _MB, per_node2=32.0),
    "equilibrium-fd": Footprint(base=90 * _MB, per_node=1.25e3),
    "polish-fourier": Footprint(base=90 * _MB, per_node=66e3, per_node2=92.0),
    "polish-fd": Footprint(base=90 * _MB, per_node=85e3),
    "spectrum-fourier": Footprint(base=90 * _MB, per_node=1e5, per_node2=900.0),
    "spectrum-fourier-noreject": Footprint(base=90 * _MB, per_node=3e4, per_node2=390.0),
    "spectrum-fd": Footprint(base=90 * _MB, per_node=1.5e4, per_node2=37.0),
    "spectrum-k-fourier": Footprint(base=90 * _MB, per_node=4e4, per_node2=335.0),
    "spectrum-k-fd": Footprint(base=90 * _MB, per_node=4.8e3),
}


def _parse_size(text):
    text = text.strip().upper().rstrip("B")
    scale = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}.get(text[-1:], 1)
    number = text[:-1] if text[-1:] in "KMGT" else text
    try:
        return int(float(number) * scale)
    except ValueError:
        raise ValueError(f"QSA_MEMORY_LIMIT={text!r}: give bytes, e.g. 8G or 512M") from None


def available_bytes() -> int:
    """Memory a run may use: ``QSA_MEMORY_LIMIT`` if set, else the available physical memory.

    Returns
    -------
    int
        Bytes (``MemAvailable`` of ``/proc/meminfo``, or ``os.sysconf`` free pages).
    """
    limit = os.environ.get("QSA_MEMORY_LIMIT")
    if limit:
        return _parse_size(limit)
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return 2**62


def format_bytes(n) -> str:
    """``1.5 GiB``, ``820 MiB``.

    Examples
    --------
    >>> format_bytes(3 * 2**30), format_bytes(5e8)
    ('3 GiB', '477 MiB')
    """
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20)):
        if n >= size:
            v = n / size
            return f"{v:.3g} {unit}" if v < 1000 else f"{v:.0f} {unit}"
    return f"{n / 2**10:.3g} KiB"


def require(args, what, estimate, hint) -> None:
    """Refuse a run whose estimated memory exceeds what is available.

    Parameters
    ----------
    args : argparse.Namespace
        Unused but for symmetry with the other command helpers.
    what : str
        The run, for the message (``"a FacetingFlow flow at N = 10000000"``).
    estimate : (float, Footprint, float)
        ``(bytes, footprint, pairs_per_N2)`` from one of the ``*_bytes`` functions.
    hint : str
        What to do instead (``"use a smaller --N"``).

    Raises
    ------
    ValueError
        ``<what> needs about X of memory (estimated), more than the Y available; <hint>``.
    """
    needed, footprint, pairs_per_N2 = estimate
    limit = available_bytes()
    if needed <= limit:
        return
    largest = footprint.largest_N(limit, pairs_per_N2)
    at_most = f" (at most about N = {largest} here)" if largest > 0 else ""
    source = "QSA_MEMORY_LIMIT" if os.environ.get("QSA_MEMORY_LIMIT") else "available"
    raise ValueError(f"{what} needs about {format_bytes(needed)} of memory (estimated), more "
                     f"than the {format_bytes(limit)} {source}; {hint}{at_most}")


def _estimate(key, N, pairs=0.0):
    fp = FOOTPRINTS[key]
    return MARGIN * fp.peak(N, pairs), fp, pairs / max(N, 1) ** 2


def adhesion_pairs_estimate(model, xy, N, n_probe=2000) -> float:
    """Node pairs within the adhesion kernel's cutoff at the initial curve, for N nodes.

    Counted on ``n_probe`` equal-chord nodes and scaled by ``(N / n_probe)^2``
    (the pairs of a fixed curve grow like N^2); 0 without adhesion.
    """
    kernel = getattr(model, "kernel", None)
    if kernel is None or getattr(model, "adhesion_method", "neighbours") != "neighbours":
        return 0.5 * N * N if kernel is not None else 0.0
    from scipy.spatial import cKDTree

    from qsa.resample import resample_closed

    x, y = (np.asarray(v, dtype=float) for v in xy)
    n = min(int(N), n_probe)
    X, Y, _ = resample_closed(x, y, n, method="chord")
    tree = cKDTree(np.column_stack([X, Y]))
    within = tree.count_neighbors(tree, kernel.cutoff_distance()) - n  # ordered, no self
    return 0.5 * within * (N / n) ** 2


def flow_bytes(model, xy, N):
    """Estimate for :func:`qsa.flows.solve_flow` of ``model`` from samples ``xy`` at N nodes."""
    if model.name == "CHA":
        return _estimate("flow-cha", N, adhesion_pairs_estimate(model, xy, N))
    return _estimate("flow-facet", N)


def equilibrium_bytes(N, fourier=True):
    """Estimate for building an equilibrium at N nodes (Fourier: dense operators)."""
    return _estimate("equilibrium-fourier" if fourier else "equilibrium-fd", N)


def polish_bytes(N, fourier=True):
    """Estimate for :func:`qsa.equilibria.polish` at N nodes."""
    return _estimate("polish-fourier" if fourier else "polish-fd", N)


def spectrum_bytes(N, fourier=True, k=None, reject=True):
    """Estimate for :func:`qsa.spectra.spectrum` at N nodes, equilibrium included.

    All eigenvalues (dense, with the two-resolution check unless ``reject`` is
    False) or the ``k`` nearest a shift (sparse shift-invert; the Fourier grid's
    operators are dense all the same).
    """
    grid = "fourier" if fourier else "fd"
    if k is not None:
        return _estimate(f"spectrum-k-{grid}", N)
    if fourier and not reject:
        return _estimate("spectrum-fourier-noreject", N)
    return _estimate(f"spectrum-{grid}", N)
