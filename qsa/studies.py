"""Study functions for :func:`qsa.sweep.run_sweep` (one point of a parameter study each).

A study is a module-level function of keyword parameters (all with defaults) that
returns a dict of scalars (table columns) and arrays (stored per point). They are
picklable by reference, so they run on a process pool or a Dask cluster.

``npulse_study``
    The N-pulse faceted equilibrium of ``Faceting + Perimeter`` (e:Facet-CP,
    e:Fint; Conventions and errata, section 5): residual, closure, L, L*, nu2, energy.
``spectrum_study``
    Its spectrum (linearization ``-MM-dagger L_Lambda``, Conventions and errata, section 4;
    :mod:`qsa.spectra`): unstable count, kernel dimension, leading eigenvalues.
``circle_spectrum_study``
    The circle's spectrum against the closed form of Conventions and errata, section 4
    (:func:`circle_eigenvalues`), on Fourier or finite-difference grids.
``splice_spectrum_study``
    The small eigenvalues of a heteroclinic splice (a rounded polygon) and the
    predicted scale ``exp(-kstar d_min / (sqrt(2) alpha))`` (Conventions and errata, section 5).
``flow_rate_study``
    A circle perturbed along an eigenfunction, evolved by the DAE faceting flow
    (:mod:`qsa.flows`): the measured growth/decay rate against the eigenvalue.

:data:`STUDIES` maps the names used by ``qsa sweep NAME`` to the functions.
"""

from __future__ import annotations

import warnings

import numpy as np

from qsa import FiniteDifference, Fourier, equilibria, spectra
from qsa.energies import DoubleWell
from qsa.equilibria import circle, npulse, splice_polygon
from qsa.flows import FacetingFlow, flow_model, solve_flow

__all__ = ["npulse_study", "spectrum_study", "circle_spectrum_study", "circle_eigenvalues",
           "splice_spectrum_study", "flow_rate_study", "mode_amplitude", "mode_decay", "STUDIES"]


def _grid(N, fd):
    if N is None:
        if fd:
            raise ValueError("N: finite differences need an explicit N")
        return None
    if isinstance(N, bool) or int(N) != N or N < 8:
        raise ValueError(f"N must be an integer >= 8, got {N!r}")
    return FiniteDifference(int(N)) if fd else Fourier(int(N))


def _npulse(n_pulses, alpha, kstar, beta, nu1, N, fd):
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
        lambda_0..`` (largest first), ``spectrum_status`` (1: not an equilibrium to
        the spectrum's tolerance) and the kernel-report numbers ``kernel_*``; array
        ``eigenvalues`` (all, largest first).
    """
    eq = _npulse(n_pulses, alpha, kstar, beta, nu1, N, fd)
    sp = _spectrum(eq)
    ev = np.sort(np.real(np.asarray(sp.eigenvalues)))[::-1]
    out = {"n_nodes": int(eq.curve.N), "converged": bool(eq.success),
           "residual": float(eq.residual), "relative_residual": float(eq.relative_residual),
           "n_unstable": int(sp.n_unstable),
           "n_kernel": int(sp.n_kernel), "spectrum_status": int(sp.status)}
    for i in range(int(n_leading)):
        out[f"lambda_{i}"] = float(ev[i]) if i < ev.size else float("nan")
    out.update(_kernel_columns(sp.kernel))
    out["eigenvalues"] = ev
    return out


def _spectrum(eq):
    """Spectrum at an (quasi-)equilibrium; "not an equilibrium" goes in ``status``, quietly."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", spectra.NotEquilibriumWarning)
        return spectra.spectrum(eq.energy, eq.curve)


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


def circle_eigenvalues(R, alpha, kstar=5.0, beta=5.0, kmax=8, well=None):
    """Closed-form eigenvalues ``lambda_k`` of ``J`` on the faceting circle, ``k = 0..kmax``.

    ``lambda_k = -((k^2 - 1)^2 / R^4) (alpha^2 k^2 / R^2 + W''(1/R)) - delta_k0 2 pi beta / R``
    (Conventions and errata, section 4): mode ``cos k theta``; ``k = 1`` (translations)
    is 0 and every ``k >= 1`` is double.

    Returns
    -------
    ndarray, shape (kmax + 1,)
    """
    well = DoubleWell(kstar) if well is None else well
    k = np.arange(int(kmax) + 1, dtype=float)
    lam = -((k**2 - 1) ** 2 / R**4) * (alpha**2 * k**2 / R**2 + float(well.d2W(1.0 / R)))
    lam[0] -= 2 * np.pi * beta / R
    return lam


def circle_spectrum_study(R=1.0, alpha=0.1, kstar=5.0, beta=5.0, N=33, fd=False, kmax=6):
    """The circle equilibrium's spectrum against :func:`circle_eigenvalues`.

    Each closed-form eigenvalue of the modes ``k <= kmax`` (doubles included) is compared
    with the nearest computed one; the expected unstable count uses every mode the grid
    carries (``k <= (N - 1) / 2``).

    Returns
    -------
    dict
        ``max_rel_error`` (over the non-zero exact eigenvalues), ``kernel_error``
        (largest computed eigenvalue where the exact one is 0), ``n_unstable``,
        ``expected_unstable``, ``n_kernel``; arrays ``eigenvalues`` (the nearest computed
        ones) and ``exact`` (modes 0, 1..kmax, 1..kmax).

    Examples
    --------
    >>> r = circle_spectrum_study(N=33)
    >>> bool(r["max_rel_error"] < 1e-8), r["n_unstable"] == r["expected_unstable"]
    (True, True)
    """
    eq = circle(R, alpha, grid=_grid(N, fd), beta=beta, kstar=kstar)
    if 2 * int(kmax) + 1 > eq.curve.N:
        raise ValueError(f"kmax={kmax} needs N >= {2 * int(kmax) + 1}")
    lam = circle_eigenvalues(R, alpha, kstar, beta, kmax)
    exact = np.concatenate([lam, lam[1:]])
    sp = spectra.spectrum(eq.energy, eq.curve)
    ev = np.real(np.asarray(sp.eigenvalues))
    # each exact eigenvalue against the nearest computed one
    nearest = ev[np.argmin(np.abs(ev[None, :] - exact[:, None]), axis=1)]
    nz = exact != 0
    lam_all = circle_eigenvalues(R, alpha, kstar, beta, (eq.curve.N - 1) // 2)
    return {"n_nodes": int(eq.curve.N),
            "max_rel_error": float(np.max(np.abs(nearest[nz] - exact[nz]) / np.abs(exact[nz]))),
            "kernel_error": float(np.max(np.abs(nearest[~nz]))),
            "n_unstable": int(sp.n_unstable),
            "expected_unstable": int(lam_all[0] > 0) + 2 * int(np.sum(lam_all[2:] > 0)),
            "n_kernel": int(sp.n_kernel), "eigenvalues": nearest, "exact": exact}


def _floats(text, name):
    try:
        vals = [float(v) for v in str(text).split(",")]
    except ValueError:
        raise ValueError(f"{name} must be comma-separated numbers, got {text!r}") from None
    return np.array(vals)


def splice_spectrum_study(alpha=0.12, angles="120,120,120", facets="1,1.4,1", kstar=5.0,
                          beta=5.0, N=None, rtol=1e-4):
    """Small eigenvalues of a splice quasi-equilibrium shaped like a rounded polygon.

    The eigenvalues of ``J`` nearest 0 come from the factored operator
    (:func:`qsa.spectra.spectrum` with ``k``), so slow eigenvalues many decades below
    ``eps |J|`` are resolved; the rigid motions are not deflated (at a quasi-equilibrium
    their normal components are only ``O(delta)``-close to an invariant subspace: they
    are among the slow eigenvalues).

    Parameters
    ----------
    alpha, kstar, beta : float
    angles, facets : str
        Comma-separated exterior corner angles (degrees, sum 360) and facet lengths
        (:func:`qsa.equilibria.splice_polygon`).
    N : int, optional
        Fourier size (default: resolving the fronts).
    rtol : float
        Relative accuracy required of the reported eigenvalues.

    Returns
    -------
    dict
        ``n_corners``, ``d_min`` (smallest front spacing), ``delta = exp(-kstar d_min /
        (sqrt(2) alpha))``, ``relative_residual``, ``n_unstable``, ``kernel_tol``,
        ``spectrum_status`` (1: a quasi-equilibrium beyond the spectrum's tolerance), the
        ``2 n_corners - 1`` slow eigenvalues as ``slow_0..`` (largest first; 3 of them
        the rigid motions, the others front motions) with their error estimates
        ``slow_error_0..``, ``fast`` (the next one); array ``eigenvalues``.
    """
    ang = np.radians(_floats(angles, "angles"))
    fac = _floats(facets, "facets")
    eq = splice_polygon(ang, fac, alpha, grid=_grid(N, False), kstar=kstar, beta=beta)
    n = len(ang)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", spectra.NotEquilibriumWarning)
        sp = spectra.spectrum(eq.energy, eq.curve, k=2 * n + 2, deflate=False, rtol=rtol)
    near = np.argsort(np.abs(sp.eigenvalues), kind="stable")
    if near.size < 2 * n:
        raise ValueError(f"alpha={alpha}: only {near.size} eigenvalues near 0 are resolved to "
                         f"rtol={rtol} ({sp.unresolved.size} unresolved); raise rtol or N")
    slow = near[: 2 * n - 1]
    slow = slow[np.argsort(-sp.eigenvalues[slow], kind="stable")]
    d_min = float(eq.params["d_min"])
    out = {"n_nodes": int(eq.curve.N), "n_corners": n, "d_min": d_min,
           "delta": float(np.exp(-kstar * d_min / (np.sqrt(2) * alpha))),
           "relative_residual": float(eq.relative_residual), "n_unstable": int(sp.n_unstable),
           "kernel_tol": float(sp.kernel_tol), "spectrum_status": int(sp.status),
           "n_unresolved": int(sp.unresolved.size)}
    for i, j in enumerate(slow):
        out[f"slow_{i}"] = float(sp.eigenvalues[j])
        out[f"slow_error_{i}"] = float(sp.errors[j])
    out["fast"] = float(sp.eigenvalues[near[2 * n - 1]])
    out["eigenvalues"] = np.sort(sp.eigenvalues)[::-1]
    return out


def mode_amplitude(x, y, k):
    """``|c_k| = |(1/pi) int r e^{-ik phi} dphi|``, ``r(phi)`` the radius about the area centroid.

    For a star-shaped closed curve sampled counter-clockwise at nodes ``(x, y)``
    (trapezoid rule in the polar angle ``phi``).
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    # about the area centroid of the polygon (independent of how the nodes are spaced)
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * cross.sum()
    xc = np.sum((x + np.roll(x, -1)) * cross) / (6 * area)
    yc = np.sum((y + np.roll(y, -1)) * cross) / (6 * area)
    phi = np.unwrap(np.arctan2(y - yc, x - xc))
    r = np.hypot(x - xc, y - yc)
    phi = np.append(phi, phi[0] + 2 * np.pi)
    f = np.append(r, r[0]) * np.exp(-1j * k * phi)
    return float(abs(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(phi))) / np.pi)


def flow_rate_study(R=1.0, alpha=0.1, kstar=5.0, beta=5.0, mode=2, amplitude=1e-3, N=128,
                    decay=2.0, tol=1e-7, n_snapshots=11):
    """Growth or decay rate of a circle's normal mode under the DAE faceting flow.

    The circle ``equilibria.circle(R, alpha)`` is perturbed along the eigenfunction
    ``cos(mode theta)`` of ``J`` (radius ``R + amplitude cos(mode theta)``) and evolved by
    :func:`qsa.flows.solve_flow` (``FacetingFlow`` with the circle's ``L*``, the paper's
    backward Euler with step doubling, ``N`` nodes) for ``decay / |lambda|``. The
    measured rate is the least-squares slope of ``log |c_mode(t)|``
    (:func:`mode_amplitude`); it is compared with the closed form
    (:func:`circle_eigenvalues`) and with ``qsa.spectra`` (Fourier grid, nearest
    eigenvalue).

    Returns
    -------
    dict
        ``rate`` (measured), ``lambda_exact``, ``lambda_spectrum``, ``rel_diff_exact``,
        ``rel_diff_spectrum``, ``t_final``, ``n_steps``, ``flow_success``; arrays ``t``
        and ``amplitude`` (of the mode at the snapshots).
    """
    k = int(mode)
    if k < 2:
        raise ValueError(f"mode must be >= 2 (0 changes the length, 1 translates), got {mode}")
    lam = float(circle_eigenvalues(R, alpha, kstar, beta, k)[k])
    eq = circle(R, alpha, grid=Fourier(4 * k + 33), beta=beta, kstar=kstar)
    ev = np.real(np.asarray(_spectrum(eq).eigenvalues))
    lam_sp = float(ev[np.argmin(np.abs(ev - lam))])
    th = 2 * np.pi * np.arange(8 * N) / (8 * N)
    r = R + amplitude * np.cos(k * th)
    t_final = abs(float(decay)) / abs(lam)
    model = FacetingFlow(alpha=alpha, kstar=kstar, beta=beta, L_star=eq.params["L_star"])
    res = solve_flow(model, (r * np.cos(th), r * np.sin(th)), t_final, N=int(N), tol=tol,
                     t_eval=np.linspace(0, t_final, int(n_snapshots)), progress=False)
    amp = np.array([mode_amplitude(*res.positions(i), k) for i in range(len(res.t))])
    rate = float(np.polyfit(res.t, np.log(amp), 1)[0])
    return {"rate": rate, "lambda_exact": lam, "lambda_spectrum": lam_sp,
            "rel_diff_exact": abs(rate - lam) / abs(lam),
            "rel_diff_spectrum": abs(rate - lam_sp) / abs(lam_sp), "t_final": t_final,
            "n_steps": int(res.n_steps), "flow_success": bool(res.success),
            "t": np.asarray(res.t), "amplitude": amp}


def mode_decay(eq, N=192, mode=None, amplitude=2e-3, efolds=3.0, tol=1e-7, snapshots=16):
    """Perturb an equilibrium along an eigenmode of J; measure the DAE decay rate.

    The equilibrium is polished on a ``FiniteDifference(N)`` grid (the flow's
    discretization); the eigenvector phi of J (normal gauge, ``<f, h> = int f h dsigma``)
    displaces the nodes normally by ``amplitude`` (max norm); the DAE flow
    (BDF2) runs for ``efolds`` e-folding times. ``V^n`` at the nodes is projected
    (least squares, uniform weights: the flow's ``dsigma = L/N``) onto the eigenspace
    of the eigenvalue (every eigenvector within ``1e-6`` of it: symmetric equilibria have
    double ones), and the rate is the slope of the log of the projection's norm over
    the later snapshots. The projection removes the faster modes that the
    perturbation's mismatch with the DAE discretization excites (they decay at
    neighbouring rates when the gap to the next eigenvalue is small, e.g. the 4-pulse);
    the first three snapshots are skipped all the same.

    Parameters
    ----------
    eq : Equilibrium
        An equilibrium of a local energy plus a perimeter penalty (faceting,
        functionalized, any second-order energy); the flow is
        :func:`qsa.flows.flow_model` of ``eq.energy``.
    N : int
        Nodes of the flow (and of the spectrum).
    mode : int, optional
        Index into the eigenvalues sorted descending; default: the first one below -1
        outside the kernel (the slowest O(1) decaying mode).

    Returns
    -------
    dict
        ``eigenvalue``, ``multiplicity``, ``measured_rate``, ``relative_error``, flow
        counters, and under ``"_flow"`` the pair (FlowResult, RMS V^n at its snapshots).
    """
    c = equilibria.polish(eq.energy, eq.curve.on_grid(FiniteDifference(N))).curve
    sp = spectra.spectrum(eq.energy, c)
    lam = sp.eigenvalues
    i = int(np.argmax((lam < -1.0) & ~sp.is_kernel)) if mode is None else int(mode)
    lam1, phi = float(lam[i]), sp.eigenvectors[:, i]
    if not lam1 < 0:
        raise ValueError(f"mode {i} has eigenvalue {lam1:.3g} >= 0: it does not decay")
    x, y = c.positions()
    nx, ny = c.normal()
    eps = amplitude / np.abs(phi).max()
    model = flow_model(eq.energy)
    T = efolds / abs(lam1)
    res = solve_flow(model, (x + eps * phi * nx, y + eps * phi * ny), T, N=N, tol=tol,
                     method="bdf2", t_eval=np.linspace(0, T, snapshots), progress=False)
    Vn = np.array([res.system.normal_velocity(s) for s in res.states])
    V = np.sqrt(np.mean(Vn**2, axis=1))
    same = np.flatnonzero((np.abs(lam - lam1) <= 1e-6 * abs(lam1)) & ~sp.is_kernel)
    basis = sp.eigenvectors[:, same]
    coef = np.linalg.lstsq(basis, Vn.T, rcond=None)[0]
    projected = np.linalg.norm(basis @ coef, axis=0) / np.sqrt(N)
    fit = slice(3, None)
    rate = float(np.polyfit(res.t[fit], np.log(projected[fit]), 1)[0])
    return {"N": N, "mode": i, "eigenvalue": lam1, "multiplicity": int(same.size),
            "measured_rate": rate,
            "relative_error": abs(rate - lam1) / abs(lam1), "t_final": T,
            "success": bool(res.success), "n_steps": int(res.n_steps),
            "max_energy_increase": float(np.max(np.diff(res.energy_steps))),
            "_flow": (res, V)}


#: Names of ``qsa sweep NAME`` -> study functions.
STUDIES = {"npulse": npulse_study, "spectrum": spectrum_study,
           "circle-spectrum": circle_spectrum_study, "splice-spectrum": splice_spectrum_study,
           "flow-rate": flow_rate_study}
