"""Slow eigenvalues of the front-position ODE against the full linearization, mode by mode.

:func:`compare_eigenvalues` takes a rounded polygon (a regular one by default), computes
the eigenpairs of the reduced Jacobian (:func:`qsa.reduction.modes.reduced_modes`) and
the eigenpairs of the full linearization nearest 0 (:func:`qsa.spectra.spectrum`,
normal gauge, shift-invert with error estimates) and pairs them by the overlap of the
eigenvectors, both written as normal perturbations of the curve
(:func:`qsa.reduction.modes.pair_modes`; the derivation of the map from front
displacements to normal perturbations is in :mod:`qsa.reduction.modes`). Sorting by
``|lambda|`` instead would pair a slow mode with whichever fast mode happens to lie
nearer 0 once the fronts overlap.

*What is compared.* A linearization is a statement about the dynamics only at a rest
point. A regular polygon's splice is one up to exponentially small terms and polishes
(:func:`qsa.equilibria.polish`) to an exact equilibrium (an N-pulse), so there the full
slow eigenvalues are the exact rates of the modes and the reduced ones are compared
with them (``equilibrium=True``). An unequal polygon is a quasi-equilibrium: its fronts
move at the rate of the slow eigenvalues themselves, so the full operator at the curve
(``L_Lambda`` with multipliers projected from a gradient that is not in ``span Psi``)
and the reduced Jacobian at the same positions (which contains the derivative of the
metric along the non-zero velocity) are linearizations of two different vector fields,
and their difference is of the size of the eigenvalues. ``polish=False`` gives that
comparison for information (``equilibrium=False``); the reduction is validated on
unequal polygons by what is intrinsic there, the dynamics (collision times and
trajectories against the DAE, :func:`qsa.paper.compare_fronts`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import newton

from qsa import Fourier
from qsa.equilibria import default_cutoff, heteroclinic
from qsa.equilibria import polish as polish_curve
from qsa.equilibria.splice import polygon_positions
from qsa.paper.results import _Summarised
from qsa.paper.scenarios import Scenario, front_scenario
from qsa.reduction import FrontODE
from qsa.reduction.manifold import quadrature_size
from qsa.reduction.modes import pair_modes, reduced_modes, trig_interpolate
from qsa.spectra import rigid_normal_basis, spectrum

__all__ = ["EigenvalueComparison", "compare_eigenvalues", "polygon_scenario"]


@dataclass(frozen=True, eq=False)
class EigenvalueComparison(_Summarised):
    """Result of :func:`compare_eigenvalues`.

    Attributes
    ----------
    scenario : Scenario
    reduced : ndarray, shape (2n - 4,)
        Slow eigenvalues of the reduced Jacobian, sorted descending (``2n - 3`` with
        ``variable_length``: the perimeter mode too; so the arrays below).
    full : ndarray, shape (2n - 4,)
        The full eigenvalue paired with each reduced one (by eigenvector overlap).
    full_errors : ndarray, shape (2n - 4,)
        Their error estimates (:attr:`qsa.spectra.Spectrum.errors`).
    rel_diff : ndarray, shape (2n - 4,)
        ``|reduced - full| / |full|``.
    cosine : ndarray, shape (2n - 4,)
        ``|<phi^full, phi^red>|`` of each pair (unit normal perturbations; within a
        degenerate pair any split of the eigenspace is as good).
    capture : ndarray, shape (2n - 4,)
        Part of each reduced mode inside the span of the computed full eigenvectors
        (1: a combination of them).
    rigid : ndarray, shape (3,)
        The rigid-motion (kernel) eigenvalues of the full spectrum.
    full_nonkernel : ndarray
        All non-kernel full eigenvalues computed (nearest 0), sorted descending.
    max_rel_diff : float
        ``max(rel_diff)``.
    equilibrium : bool
        The full spectrum is taken at a polished equilibrium (else at the splice).
    polish_residual : float
        Relative residual of the polished curve (NaN without polishing).
    polish_success : bool
    spectrum_status : int
        :attr:`qsa.spectra.Spectrum.status`.
    N : int
        Fourier nodes of the full linearization.
    correction : None or "newton"
        Force of the reduction.
    min_facet : float
        Smallest facet of the splice.
    length : str
        Where the reduction was linearized (``"splice"`` or ``"equilibrium"``).
    variable_length : bool
        The reduction had the length as an unknown (its perimeter mode is the
        extra pair).
    length_offset : float
        Length of the reduction's linearization point minus the polished
        equilibrium's (NaN without polishing).
    perimeter_index : int
        With ``variable_length``: the index of the perimeter mode among the reduced
        ones (the largest change of length per front displacement); else -1.
    """

    scenario: Scenario
    reduced: np.ndarray
    full: np.ndarray
    full_errors: np.ndarray
    rel_diff: np.ndarray
    cosine: np.ndarray
    capture: np.ndarray
    rigid: np.ndarray
    full_nonkernel: np.ndarray
    max_rel_diff: float
    equilibrium: bool
    polish_residual: float
    polish_success: bool
    spectrum_status: int
    N: int
    correction: str | None
    min_facet: float
    length: str = "splice"
    variable_length: bool = False
    length_offset: float = np.nan
    perimeter_index: int = -1

    @property
    def n_corners(self):
        return len(self.scenario.angles)

    def __getitem__(self, key):
        """``result["max_rel_diff"]``: the dictionary access of earlier versions (deprecated)."""
        warnings.warn("compare_eigenvalues returns an EigenvalueComparison: use its attributes "
                      "(or summary()[key]) instead of result[key]", DeprecationWarning,
                      stacklevel=2)
        return self.summary()[key]

    def summary(self):
        return {"scenario": self.scenario.name, "n_corners": self.n_corners,
                "facets": list(self.scenario.facets), "min_facet": self.min_facet,
                "correction": self.correction, "reduced": self.reduced.tolist(),
                "full": self.full.tolist(), "full_errors": self.full_errors.tolist(),
                "rel_diff": self.rel_diff.tolist(), "cosine": self.cosine.tolist(),
                "capture": self.capture.tolist(), "rigid": self.rigid.tolist(),
                "max_rel_diff": self.max_rel_diff, "equilibrium": self.equilibrium,
                "polish_residual": self.polish_residual,
                "polish_success": self.polish_success,
                "spectrum_status": self.spectrum_status, "N": self.N, "pairing": "overlap",
                "length": self.length, "variable_length": self.variable_length,
                "length_offset": self.length_offset, "perimeter_index": self.perimeter_index}


def polygon_scenario(n_corners, facet=0.35, angles=None, facets=None):
    """The regular polygon with ``n_corners`` facets ``facet``, or that of ``angles``/``facets``.

    ``angles`` in degrees (exterior, summing to 360); the facets are closed by
    :func:`qsa.equilibria.splice_polygon`.
    """
    n = int(n_corners)
    sc = Scenario.regular(n, facet)
    if angles is None and facets is None:
        return sc
    return Scenario("polygon", tuple(sc.angles if angles is None else angles),
                    tuple(sc.facets if facets is None else facets),
                    f"polygon with {n} corners", sc.t_final)


def _is_regular(sc):
    return np.ptp(sc.angles) < 1e-12 and np.ptp(sc.facets) < 1e-12


def compare_eigenvalues(scenario=3, facet=0.35, alpha=None, kstar=None, N=None, angles=None,
                        facets=None, *, correction=None, polish=None, extra=None, rtol=1e-4,
                        length="splice", variable_length=False):
    """Slow eigenvalues of the reduced Jacobian against the full linearization, paired by mode.

    Parameters
    ----------
    scenario : int, str or Scenario
        A number of corners (the regular polygon with facets ``facet``, or the
        polygon of ``angles`` in degrees and ``facets``), or a front scenario.
    facet, angles, facets
        Only with a number of corners.
    alpha, kstar : float, optional
        Replace the scenario's (default 0.1 and 5).
    N : int, optional
        Fourier nodes of the full linearization (odd); default three per front
        width ``1/lambda`` (:func:`qsa.reduction.manifold.quadrature_size`), where the
        slow eigenvalues are converged to ~1e-5.
    correction : {None, "newton", "profile", "profile-lag"}
        The reduction's manifold and force (:class:`qsa.reduction.FrontODE`).
    polish : bool, optional
        Take the full spectrum at the polished equilibrium (default: for regular
        polygons) or at the splice itself (the operator at a quasi-equilibrium; see
        the module docstring for what that comparison means).
    extra : int, optional
        Full eigenvalues computed beyond the ``2n - 4`` slow and 3 rigid ones
        (default ``2n``): candidates for the pairing.
    rtol : float
        Relative accuracy required of a full eigenvalue
        (:func:`qsa.spectra.spectrum`; far below the differences compared).
    length : {"splice", "equilibrium"}
        Where the reduction is linearized: at the splice of the scenario (length
        ``L*``), or, for a polished regular polygon, at the same rest point as the
        full spectrum -- the regular splice of the polished N-pulse's length (the
        perimeter penalty lets the overlapping corners lengthen the curve: the
        octagon with facets 0.35 by 1.7e-3, which moves its facet eigenvalues by
        0.7%). With ``variable_length`` on a regular polygon ``"splice"`` is the
        reduction's own rest point: the regular splice of the length where
        ``L' = 0`` (on the profile manifold the N-pulse's length;
        :attr:`EigenvalueComparison.length_offset`).
    variable_length : bool
        Linearize the reduction with the length as an unknown
        (``FrontODE(beta=scenario.beta)``, the full problem's perimeter penalty):
        ``2n - 3`` reduced modes, the perimeter mode among them, all paired.

    Returns
    -------
    EigenvalueComparison

    Examples
    --------
    >>> r = compare_eigenvalues(3, facet=0.4, correction="newton")
    >>> r.reduced.size, bool(r.max_rel_diff < 0.01), bool(min(r.capture) > 0.9999)
    (2, True, True)
    """
    if isinstance(scenario, (int, np.integer)):
        sc = polygon_scenario(scenario, facet, angles, facets)
    else:
        sc = scenario
    sc = front_scenario(sc, alpha=alpha, kstar=kstar)
    if N is None:
        L0 = sc.splice().params["L"]
        N = quadrature_size(L0, heteroclinic(sc.alpha, kstar=sc.kstar).width, 3.0)
    if length not in ("splice", "equilibrium"):
        raise ValueError(f"length must be 'splice' or 'equilibrium', got {length!r}")
    eq = sc.splice(Fourier(N))
    p = np.array(eq.params["positions"])
    L = eq.params["L"]
    cut = tuple(eq.params["cutoff"])
    do_polish = _is_regular(sc) if polish is None else bool(polish)
    if length == "equilibrium" and not (do_polish and _is_regular(sc)):
        raise ValueError("length='equilibrium' needs a regular polygon with polish")
    curve, energy = eq.curve, eq.energy
    pol_res, pol_ok = np.nan, False
    if do_polish:
        pol = polish_curve(eq.energy, eq.curve)
        curve, energy = pol.curve, pol.energy
        pol_res, pol_ok = float(pol.residual), bool(pol.success)
    L_star, L_full = L, (curve.length() if do_polish else np.nan)
    if length == "equilibrium":
        p, L = _regular_splice(sc, L_full - L_star)
        cut = default_cutoff(p, L)
    if variable_length:  # the perimeter penalty of the full problem, L* the splice's
        ode = FrontODE(sc.alpha, sc.kstar, L_star, correction=correction, beta=sc.beta)
        if length == "splice" and _is_regular(sc):
            p, L = _regular_splice(sc, _rest_length(ode, sc, cut))
        red = reduced_modes(ode, p, cut, L)
    else:
        ode = FrontODE(sc.alpha, sc.kstar, L, correction=correction)
        red = reduced_modes(ode, p, cut)
    m = red.eigenvalues.size
    k = m + 3 + (2 * len(sc.angles) if extra is None else int(extra))
    with warnings.catch_warnings():
        # at a splice (no polish) the curve is a quasi-equilibrium by design
        warnings.simplefilter("ignore")
        spec = spectrum(energy, curve, k=k, rtol=rtol)
    kern = spec.is_kernel
    if not np.any(kern):  # nothing deflated: the rigid ones are the modes nearest them
        R = rigid_normal_basis(curve)
        rigid_part = np.sum((R @ (curve.dsigma[:, None] * spec.eigenvectors)) ** 2, axis=0)
        kern = np.zeros(spec.eigenvalues.size, dtype=bool)
        kern[np.argsort(-rigid_part)[:R.shape[0]]] = True
    lam, err = spec.eigenvalues[~kern], spec.errors[~kern]
    s = np.concatenate([[0.0], np.cumsum(curve.dsigma)[:-1]]) / curve.length()
    pairing = pair_modes(spec.eigenvectors[:, ~kern], trig_interpolate(red.normals, s),
                         curve.dsigma)
    full = lam[pairing.index]
    rel = np.abs(red.eigenvalues - full) / np.abs(full)
    gaps = np.diff(np.append(p, p[0] + L))
    return EigenvalueComparison(
        sc, red.eigenvalues, full, err[pairing.index], rel, pairing.cosine, pairing.capture,
        np.sort(spec.eigenvalues[kern]), np.sort(lam)[::-1], float(rel.max()), do_polish,
        pol_res, pol_ok, int(spec.status), int(N), correction, float(gaps[1::2].min()),
        length, bool(variable_length), float(L - L_full),
        int(np.argmax(np.abs(red.displacements[-1]))) if variable_length else -1)


def _regular_splice(sc, dL):
    """Positions and length of the scenario's polygon with every facet longer by dL / n."""
    n = len(sc.angles)
    return polygon_positions(np.deg2rad(sc.angles), np.asarray(sc.facets) + dL / n, sc.kstar)


def _rest_length(ode, sc, cut):
    """``L - L*`` where the variable-length reduction rests on the regular polygon.

    By symmetry ``p' = 0`` on the regular splices; ``L'`` is a smooth function of
    their length, whose root the secant method finds (to ~1e-14 of ``L``).
    """
    def rate(dL):
        p, L = _regular_splice(sc, dL)
        return ode.velocity_length(p, L, cut)[1]

    return float(newton(rate, 0.0, x1=1e-4 * ode.length, tol=1e-14 * ode.length,
                        maxiter=50))
