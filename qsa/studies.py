"""Study functions for :func:`qsa.sweep.run_sweep` (one point of a parameter study each).

A study is a module-level function of keyword parameters (all with defaults) that
returns a dict of scalars (table columns) and arrays (stored per point). They are
picklable by reference, so they run on a process pool or a Dask cluster.

``npulse_study``
    The N-pulse faceted equilibrium of ``Faceting + Perimeter`` (e:Facet-CP,
    e:Fint; MATH.md section 5): residual, closure, L, L*, nu2, energy.
``spectrum_study``
    Its spectrum (linearization ``-MM-dagger L_Lambda``, MATH.md section 4;
    :mod:`qsa.spectra`): unstable count, kernel dimension, leading eigenvalues.

:data:`STUDIES` maps the names used by ``qsa sweep NAME`` to the functions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["npulse_study", "spectrum_study", "STUDIES"]


def _grid(N, fd):
    from qsa import FiniteDifference, Fourier

    if N is None:
        if fd:
            raise ValueError("N: finite differences need an explicit N")
        return None
    if isinstance(N, bool) or int(N) != N or N < 8:
        raise ValueError(f"N must be an integer >= 8, got {N!r}")
    return FiniteDifference(int(N)) if fd else Fourier(int(N))


def _npulse(n_pulses, alpha, kstar, beta, nu1, N, fd):
    from qsa.equilibria import npulse

    if isinstance(n_pulses, float) and n_pulses.is_integer():
        n_pulses = int(n_pulses)
    return npulse(n_pulses, alpha, grid=_grid(N, fd), nu1=nu1, beta=beta, kstar=kstar)


def npulse_study(n_pulses=3, alpha=0.1, kstar=5.0, beta=5.0, nu1=0.0, N=None, fd=False):
    """The N-pulse equilibrium at one parameter point.

    Parameters
    ----------
    n_pulses : int
    alpha, kstar, beta, nu1 : float
        As in :func:`qsa.equilibria.npulse`.
    N : int, optional
        Grid size (default: the Fourier size resolving the fronts).
    fd : bool
        Finite differences (needs ``N``) instead of Fourier.

    Returns
    -------
    dict
        Scalars ``n_nodes`` (grid size), ``converged`` (the construction met its
        tolerance), ``residual``, ``relative_residual``, ``closure``, ``L``, ``L_star``,
        ``nu2``, ``energy``; arrays ``kappa``, ``g``.

    Examples
    --------
    >>> r = npulse_study(n_pulses=3, alpha=0.1)
    >>> r["converged"], r["L"] < r["L_star"]
    (True, True)
    """
    eq = _npulse(n_pulses, alpha, kstar, beta, nu1, N, fd)
    p = eq.params
    return {"n_nodes": int(eq.curve.N), "converged": bool(eq.success),
            "residual": float(eq.residual), "relative_residual": float(eq.relative_residual),
            "closure": float(eq.closure), "L": float(p["L"]), "L_star": float(p["L_star"]),
            "nu2": float(p["nu2"]), "energy": float(eq.energy.energy(eq.curve)),
            "kappa": np.asarray(eq.curve.kappa), "g": np.asarray(eq.curve.g)}


def spectrum_study(n_pulses=3, alpha=0.1, kstar=5.0, beta=5.0, nu1=0.0, N=None, fd=False,
                   n_leading=4):
    """Spectrum of the N-pulse equilibrium at one parameter point.

    Parameters
    ----------
    n_pulses, alpha, kstar, beta, nu1, N, fd
        As in :func:`npulse_study`.
    n_leading : int
        Number of leading (largest) eigenvalues reported as columns ``lambda_0, ...``.

    Returns
    -------
    dict
        Scalars ``n_nodes, converged, residual, relative_residual, n_unstable, n_kernel,
        lambda_0..`` (largest first) and the kernel-report numbers ``kernel_*``; array
        ``eigenvalues`` (all, largest first).
    """
    from qsa import spectra

    eq = _npulse(n_pulses, alpha, kstar, beta, nu1, N, fd)
    sp = spectra.spectrum(eq.energy, eq.curve)
    ev = np.sort(np.real(np.asarray(sp.eigenvalues)))[::-1]
    out = {"n_nodes": int(eq.curve.N), "converged": bool(eq.success),
           "residual": float(eq.residual), "relative_residual": float(eq.relative_residual),
           "n_unstable": int(sp.n_unstable),
           "n_kernel": int(sp.n_kernel)}
    for i in range(int(n_leading)):
        out[f"lambda_{i}"] = float(ev[i]) if i < ev.size else float("nan")
    out.update(_kernel_columns(sp.kernel))
    out["eigenvalues"] = ev
    return out


def _kernel_columns(report) -> dict:
    """The numeric fields of a KernelReport (whatever it carries) as ``kernel_*`` columns."""
    out = {}
    if report is None:
        return out
    items = (report.summary().items() if hasattr(report, "summary")
             else vars(report).items())
    for k, v in items:
        if isinstance(v, (bool, int, float, np.number)) and not isinstance(v, np.bool_):
            out[f"kernel_{k}"] = v.item() if isinstance(v, np.generic) else v
    return out


#: Names of ``qsa sweep NAME`` -> study functions.
STUDIES = {"npulse": npulse_study, "spectrum": spectrum_study}
