"""The spectrum of the linearized flow at an equilibrium, every eigenvalue with an error bound.

:func:`spectrum` is a short sequence of named steps:

1. :func:`check_arguments` -- bad input raises ``ValueError`` naming the argument;
2. the Lagrangian Hessian and the distance from equilibrium (a
   :class:`NotEquilibriumWarning` when the curve is not one);
3. the solve (:mod:`qsa.spectra.solvers`): in the normal gauge the slow eigenvalues come
   from the factored operator with the rigid motions deflated
   (:mod:`qsa.spectra.factored`), so their error scales with the mode, not with
   ``|J|``; all eigenvalues (``k=None``) combine the formed matrix for the fast
   ones with the factors near 0; the non-normal gauges use the formed matrix with
   condition-number error estimates;
4. :func:`certify` -- the kernel (the deflated rigid modes and any eigenvalue
   indistinguishable from them, :func:`~qsa.spectra.kernel.kernel_size`) and the
   accuracy test: an eigenvalue is reported only if its error estimate is at most
   ``rtol |lambda|``; the others go to ``Spectrum.unresolved`` with an
   :class:`UnresolvedEigenvalueWarning`;
5. :func:`reject_spurious` -- optionally, the same solve at about 1.5 times the
   resolution and the drift test of each eigenvalue (the inverse of the drift ratio of
   two-resolution spurious-mode rejection);
6. the kernel report and the :class:`~qsa.spectra.result.Spectrum`.

Error estimates are of the eigenvalues of the discrete operator (round-off and solver);
the discretization error is measured by the two-resolution drift.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse.linalg as spla

from qsa._checks import real_number
from qsa.constraints import bind_constraints
from qsa.curve import Curve, check_simple
from qsa.discretize import FiniteDifference, Fourier
from qsa.spectra.factored import FactoredNormalOperator
from qsa.spectra.hessian import check_input, lagrange_hessian
from qsa.spectra.kernel import build_kernel_report, constraint_bases, kernel_size, lanczos_norm
from qsa.spectra.linearization import _check_gauge, linearization, scaled_operator
from qsa.spectra.result import MESSAGES, KernelReport, Spectrum
from qsa.spectra.solvers import (
    EigenSolution,
    certified_eigenpairs,
    dense_normal,
    general_eigenpairs,
)

__all__ = ["Spectrum", "KernelReport", "MESSAGES", "spectrum", "NotEquilibriumWarning",
           "UnresolvedEigenvalueWarning", "second_resolution", "small_cluster",
           "reject_spurious", "certify", "check_arguments"]

_EPS = np.finfo(float).eps


class NotEquilibriumWarning(UserWarning):
    """The analysed curve is not (close to) an equilibrium: the spectrum is not a linearization.

    Examples
    --------
    >>> import warnings
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     s = spectrum(Faceting(0.1, 5.0) + Perimeter(5.0, 6.0), c)
    >>> any(issubclass(x.category, NotEquilibriumWarning) for x in w), s.status
    (True, 1)
    """


class UnresolvedEigenvalueWarning(UserWarning):
    """Some computed eigenvalues failed the accuracy test and are not reported as eigenvalues.

    They are in ``Spectrum.unresolved`` with their error estimates.
    """


# ------------------------------------------------------------------ step 1: arguments
def check_arguments(energy, curve, k, sigma, gauge, kernel_tol, drift_tol, factor, rtol):
    """Validate the arguments of :func:`spectrum`; return ``(k, sigma, kernel_tol)``.

    Raises
    ------
    ValueError
        Naming the bad argument.
    """
    check_input(energy, curve)
    check_simple(curve)
    _check_gauge(gauge)
    if k is not None:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k must be a positive integer, got {k!r}")
        n = curve.N + (curve.N if gauge in ("comoving", "paper") else 0)
        if k > n - 2:
            raise ValueError(f"k={k} is too large for a problem of size {n}: use k=None "
                             "(dense) or k <= n - 2")
    if sigma is not None:
        sigma = float(sigma)
        if not np.isfinite(sigma):
            raise ValueError(f"sigma must be finite, got {sigma}")
    elif k is not None:
        sigma = 0.0
    if kernel_tol is not None:
        kernel_tol = real_number(kernel_tol, "kernel_tol", positive=True)
    if not (np.isfinite(drift_tol) and drift_tol > 0):
        raise ValueError(f"drift_tol must be positive, got {drift_tol}")
    if not (np.isfinite(factor) and 1.1 <= factor <= 4):
        raise ValueError(f"factor must be in [1.1, 4], got {factor}")
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    return k, sigma, kernel_tol


# --------------------------------------------------------------------- step 3: solve
def solve(energy, curve: Curve, gauge, k=None, sigma=None, rtol=1e-5, lagrange=None,
          vectors=True, deflate=True, constraints=None) -> EigenSolution:
    """Eigenpairs with error estimates in a gauge (the solve step of :func:`spectrum`).

    Parameters
    ----------
    energy : Energy
    curve : Curve
    gauge : {"normal", "comoving", "scaled", "paper"}
    k : int, optional
        The ``k`` eigenvalues nearest ``sigma``; default all.
    sigma : float, optional
    rtol : float
        Dense normal-gauge path: eigenvalues of the formed matrix with an error above
        ``rtol |lambda|`` are recomputed from the factors.
    lagrange : LagrangeHessian, optional
    vectors : bool
    deflate : bool
        Normal gauge: deflate the rigid motions (exact at an equilibrium, where their
        normal components span an invariant subspace of ``J``).
    constraints : sequence of Constraint, optional
        Length / area constraints: the constrained linearization (their normal
        variations excluded, :func:`~qsa.spectra.kernel.constraint_bases`). Taken from
        ``lagrange`` when it is given.

    Returns
    -------
    EigenSolution
    """
    if lagrange is not None:
        LH, cons = lagrange, lagrange.constraints
    else:
        cons = bind_constraints(constraints, curve)
        LH = lagrange_hessian(energy, curve, constraints=cons)
    w = curve.dsigma
    if gauge == "normal":
        op = FactoredNormalOperator.from_lagrangian(curve, LH.matrix, LH.energy_hessian)
        rigid_basis, cbasis = constraint_bases(curve, cons)
        basis, rigid = rigid_basis, None
        if not deflate:
            basis, rigid = np.zeros((0, curve.N)), op.ritz_values(rigid_basis)
        if k is None:
            return dense_normal(op, basis, rtol, vectors=vectors, rigid=rigid, constrain=cbasis)
        sol = certified_eigenpairs(op, basis, k=k, sigma=0.0 if sigma is None else sigma,
                                   rigid=rigid, constrain=cbasis)
        order = np.argsort(-sol.values, kind="stable")
        assert sol.vectors is not None  # certified_eigenpairs always returns vectors
        return EigenSolution(sol.values[order], sol.vectors[:, order], sol.errors[order],
                             sol.is_kernel[order], sol.method)
    if gauge == "scaled":
        A = scaled_operator(energy, curve, lagrange=LH)
        weights = np.append(w, curve.length())
    else:
        A = linearization(energy, curve, gauge=gauge, lagrange=LH)
        weights = np.concatenate([w, w])
    return general_eigenpairs(A, weights, k=k, sigma=0.0 if sigma is None else sigma,
                              real=gauge != "paper", vectors=vectors)


# ------------------------------------------------------------------- step 4: certify
def certify(sol: EigenSolution, rtol, kernel_tol=None):
    """Split eigenvalues into the reported (kernel or accurate to ``rtol``) and the unresolved.

    The kernel is the deflated rigid modes, the eigenvalues that are zero within their
    error, and those with ``|lambda| <= kernel_tol`` when it is given
    (:func:`~qsa.spectra.kernel.kernel_size`); every other eigenvalue is reported only if
    its error is at most ``rtol |lambda|``.

    Parameters
    ----------
    sol : EigenSolution
    rtol : float
    kernel_tol : float, optional

    Returns
    -------
    reported : EigenSolution
        With ``is_kernel`` marking the whole kernel.
    unresolved : ndarray
    unresolved_errors : ndarray
    kernel_tol : float
        ``max |lambda| + error`` over the kernel (at least ``kernel_tol`` when given).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.spectra.solvers import EigenSolution
    >>> sol = EigenSolution(np.array([2.0, 1e-9, -1.0, -3.0]), np.eye(4),
    ...                     np.array([1e-12, 1e-10, 0.5, 1e-11]),
    ...                     np.array([False, True, False, False]), "test")
    >>> rep, bad, bad_err, tol = certify(sol, rtol=1e-6)
    >>> rep.values.tolist(), bad.tolist(), round(tol, 12)
    ([2.0, 1e-09, -3.0], [-1.0], 1.1e-09)
    """
    vals = np.asarray(sol.values)
    err = np.asarray(sol.errors, dtype=float)
    marked = np.asarray(sol.is_kernel, dtype=bool)
    if kernel_tol is not None:
        marked = marked | (np.abs(vals) <= kernel_tol)
    _, tol = kernel_size(vals, err, marked)
    kernel = marked | (np.abs(vals) <= err)
    if kernel_tol is not None:
        tol = max(tol, kernel_tol)
    ok = kernel | (err <= rtol * np.abs(vals))
    reported = EigenSolution(vals[ok], None if sol.vectors is None else sol.vectors[:, ok],
                             err[ok], kernel[ok], sol.method, sol.roundoff, sol.max_imag,
                             sol.notes)
    return reported, vals[~ok], err[~ok], float(tol)


# ------------------------------------------------------------ step 5: spurious modes
def second_resolution(grid, factor=1.5):
    """The grid of about ``factor`` times the resolution (odd N for Fourier).

    Parameters
    ----------
    grid : Grid
    factor : float

    Returns
    -------
    Grid
        Same kind, about ``factor * grid.N`` nodes.

    Examples
    --------
    >>> from qsa import Fourier
    >>> second_resolution(Fourier(17))
    Fourier(27)
    """
    N2 = int(round(factor * grid.N))
    if isinstance(grid, Fourier):
        N2 += 1 - N2 % 2
        return Fourier(N2)
    return FiniteDifference(N2)


def reject_spurious(eigenvalues, eigenvalues2, drift_tol=1e-6, atol=0.0):
    """Two-resolution drift test: which eigenvalues persist at a second resolution.

    An eigenvalue ``lambda`` is kept when the nearest eigenvalue ``lambda2`` of the
    second solve satisfies ``|lambda - lambda2| <= max(drift_tol |lambda|, atol)``.

    Parameters
    ----------
    eigenvalues : array_like, shape (m,)
    eigenvalues2 : array_like, shape (m2,)
    drift_tol : float
        Largest relative drift of a kept eigenvalue.
    atol : float or array_like, shape (m,)
        Absolute drift always accepted (e.g. the error estimates, or the kernel level).

    Returns
    -------
    keep : ndarray of bool, shape (m,)
    drift : ndarray, shape (m,)
        ``|lambda - lambda2| / |lambda|``.

    Examples
    --------
    >>> keep, drift = reject_spurious([-1.0, -2.0, -900.0], [-1.0 + 1e-9, -2.0, -500.0, -7e3])
    >>> keep.tolist(), bool(drift[2] > 0.4)
    ([True, True, False], True)
    """
    vals = np.asarray(eigenvalues)
    vals2 = np.asarray(eigenvalues2)
    if vals2.size == 0:
        return np.zeros(vals.size, bool), np.full(vals.size, np.inf)
    dist = np.array([np.min(np.abs(vals2 - lam)) for lam in vals])
    drift = dist / np.maximum(np.abs(vals), 1e-300)
    keep = (dist <= drift_tol * np.abs(vals)) | (dist <= np.asarray(atol, dtype=float))
    return keep, drift


_drift_test = reject_spurious  # the name is also a keyword of spectrum()


def small_cluster(eigenvalues, n_kernel=0, floor=0.0, max_size=None):
    """``(m, ratio)``: size of the cluster of small eigenvalues and its separation.

    ``|lambda|`` sorted increasingly and floored at ``floor``; ``m`` maximises
    ``|lambda|_(m) / |lambda|_(m-1)`` over ``max(n_kernel, 1) <= m <= max_size``
    (default: half the number of eigenvalues). See :class:`Spectrum` ``n_small``.

    Parameters
    ----------
    eigenvalues : array_like, shape (n,)
    n_kernel : int
        Lower bound of the cluster size.
    floor : float
        Round-off level: smaller ``|lambda|`` count as ``floor``.
    max_size : int, optional

    Returns
    -------
    m : int
    ratio : float
        ``|lambda|_(m) / |lambda|_(m-1)``.

    Examples
    --------
    >>> m, ratio = small_cluster([-1e-6, 2e-6, -3e-6, -1.0, -2.0, -5.0], floor=1e-12)
    >>> m, round(ratio)
    (3, 333333)
    """
    a = np.sort(np.abs(np.asarray(eigenvalues)))
    if a.size < 2:
        return int(a.size), np.nan
    a = np.maximum(a, max(floor, 1e-300))
    hi = min(a.size - 1, max_size if max_size is not None else a.size // 2)
    lo = max(int(n_kernel), 1)
    if lo > hi:
        return int(min(lo, a.size)), np.nan
    ratios = a[lo: hi + 1] / a[lo - 1: hi]
    j = int(np.argmax(ratios))
    return lo + j, float(ratios[j])


# -------------------------------------------------------------------------- driver
def spectrum(energy, curve: Curve, k=None, sigma=None, gauge="normal", *, kernel_tol=None,
             reject_spurious=None, drift_tol=1e-6, factor=1.5, equilibrium_tol=1e-6,
             rtol=1e-5, deflate=None, constraints=None):
    """Eigenvalues and eigenvectors of the linearization at an equilibrium, with error bounds.

    Parameters
    ----------
    energy : Energy
    curve : Curve
        An equilibrium or quasi-equilibrium (else a :class:`NotEquilibriumWarning`
        is issued and ``status = 1``).
    k : int, optional
        Number of eigenvalues nearest ``sigma`` (shift-invert). Default: all of them.
    sigma : float, optional
        Shift for ``k`` (default 0). The eigenvalues do not depend on it beyond their
        error estimates.
    gauge : {"normal", "comoving", "scaled", "paper"}
        The linearization (:func:`~qsa.spectra.linearization`); default ``"normal"``
        (``J``, whose spectrum equals the non-zero spectrum of the comoving operator).
    kernel_tol : float, optional
        Also count ``|lambda| <= kernel_tol`` as kernel; default: the rigid modes'
        level (see :func:`certify`).
    reject_spurious : bool, optional
        Two-resolution check; default True for Fourier grids with ``k=None``.
    drift_tol : float
        Largest relative drift of a kept eigenvalue.
    factor : float
        Resolution ratio of the check (about 1.5).
    equilibrium_tol : float
        Warn when ``max|V^n|`` relative to its largest term exceeds this and ``max|V^n|``
        is above 100 times its round-off floor (:func:`qsa.energies.residual_floor`:
        on fine grids ``V^n`` cannot be evaluated more accurately).
    rtol : float
        Relative accuracy required of a reported eigenvalue (kernel modes excepted).
    deflate : bool, optional
        Solve on the complement of the rigid motions' normal components and report
        their Ritz values as the kernel (normal gauge). Default: at an equilibrium
        (``max|V^n|`` within ``equilibrium_tol``), where they span an invariant subspace
        of ``J``; away from one they do not, and the whole spectrum of ``J`` is computed.
    constraints : sequence of Constraint, optional
        Length / area constraints (:mod:`qsa.constraints`; ``None`` targets: the curve's
        values). The linearization of the constrained flow: ``L_Lambda`` with the
        multiplier terms ``- mu_c nabla^2 c``, and in the normal gauge ``P J P`` on
        ``T = {phi : <n_c, phi> = 0}`` (``n_L = kappa``, ``n_A = 1``; ``P`` the
        ``<.,.>``-orthogonal projection onto ``T``). The directions ``n_c`` are excluded
        from the problem (``N - m`` eigenvalues), not reported as eigenvalues; in the
        other gauges the projection is applied to the normal velocity and they add
        ``m`` kernel modes.

    Returns
    -------
    Spectrum

    Raises
    ------
    ValueError
        Bad ``energy``, ``curve`` (also one that crosses or touches itself: the message
        names the closest pair of nodes), ``gauge``, ``k``, ``sigma``, ``kernel_tol``,
        ``drift_tol``, ``factor`` or ``rtol``.

    Examples
    --------
    >>> from qsa import Fourier
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=Fourier(33))
    >>> s = spectrum(eq.energy, eq.curve)
    >>> s.n_unstable, s.n_kernel, round(float(s.eigenvalues[2]), 6)  # lambda_2 = -9 * 0.54
    (0, 2, -4.86)
    >>> bool(s.errors[2] < 1e-10)
    True
    """
    check_reject = reject_spurious
    k, sigma, kernel_tol = check_arguments(energy, curve, k, sigma, gauge, kernel_tol,
                                           drift_tol, factor, rtol)
    if check_reject is None:
        check_reject = isinstance(curve.grid, Fourier) and k is None

    cons = bind_constraints(constraints, curve)
    LH = lagrange_hessian(energy, curve, constraints=cons)
    status, notes = 0, []
    if not LH.is_equilibrium(equilibrium_tol):
        status = 1
        text = (f"the curve is not an equilibrium: max|V^n| is {LH.relative_residual:.2e} of "
                f"its largest term ({LH.residual / max(LH.residual_floor, 1e-300):.1e} times "
                f"its round-off floor), projection residual |grad E - Lambda.Psi| = "
                f"{LH.projection_residual:.3e} ({LH.relative_projection_residual:.1e} relative); "
                "the eigenvalues are those of the operator at this curve, not of a "
                "linearization about an equilibrium")
        warnings.warn(text, NotEquilibriumWarning, stacklevel=2)
        notes.append(text)
    if deflate is None:
        deflate = LH.is_equilibrium(equilibrium_tol)
    op = FactoredNormalOperator.from_lagrangian(curve, LH.matrix, LH.energy_hessian)
    basis, cbasis = constraint_bases(curve, cons)

    try:
        sol = solve(energy, curve, gauge, k, sigma, rtol, lagrange=LH, deflate=bool(deflate))
    except (np.linalg.LinAlgError, spla.ArpackError, spla.ArpackNoConvergence,
            RuntimeError) as exc:
        return _failed(curve, LH, op, basis, gauge, k, sigma, rtol, exc)
    ktol = kernel_tol
    if gauge != "normal" and ktol is None:
        # no deflation here: the kernel is J's (the rigid level) plus the reparameterization
        # modes, zero to the round-off of the formed matrix
        rvals, _, rerr = op.ritz(basis)
        ktol = max(float(np.max(np.abs(rvals) + rerr, initial=0.0)), 10 * sol.roundoff)
    reported, unresolved, unresolved_err, tol = certify(sol, rtol, ktol)

    spurious = np.array([], dtype=reported.values.dtype)
    drift = np.full(reported.values.size, np.nan)
    N2 = None
    if check_reject:
        grid2 = second_resolution(curve.grid, factor)
        N2 = grid2.N
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotEquilibriumWarning)
            sol2 = solve(energy, curve.on_grid(grid2), gauge, k, sigma, rtol, vectors=False,
                         deflate=bool(deflate), constraints=cons)
        _, tol2 = kernel_size(sol2.values, sol2.errors, sol2.is_kernel)
        keep, drift = _drift_test(reported.values, sol2.values, drift_tol,
                                  atol=np.maximum(max(tol, tol2), reported.errors))
        spurious = reported.values[~keep]
        drift = drift[keep]
        reported = EigenSolution(reported.values[keep],
                                 None if reported.vectors is None else reported.vectors[:, keep],
                                 reported.errors[keep], reported.is_kernel[keep],
                                 reported.method, reported.roundoff, reported.max_imag)
    vals, err, is_kernel = reported.values, reported.errors, reported.is_kernel
    re = np.real(vals)
    n_unstable = int(np.sum((~is_kernel) & (re > err) & (re > 0)))
    n_kernel = int(np.sum(is_kernel))
    kvals = n_kernel if gauge == "normal" else None
    kr = build_kernel_report(curve, LH, op, basis, kvals, tol, energy)

    if unresolved.size:
        if status == 0:
            status = 2
        text = (f"{unresolved.size} eigenvalue estimate(s) failed the accuracy test "
                f"(error > rtol |lambda|, rtol = {rtol:g}) and are not reported: "
                f"{np.array2string(np.real(unresolved[:6]), precision=4)}"
                f"{' ...' if unresolved.size > 6 else ''} (Spectrum.unresolved)")
        warnings.warn(text, UnresolvedEigenvalueWarning, stacklevel=2)
        notes.append(text)
    mc = cbasis.shape[0]
    expected = basis.shape[0] + {"comoving": curve.N + mc, "paper": curve.N + mc,
                                 "scaled": 1 + mc}.get(gauge, 0)
    if n_kernel != expected and (k is None or n_kernel > expected):
        notes.append(f"{n_kernel} eigenvalues in the kernel, {expected} expected"
                     + (" (the 2N x 2N operator has spurious eigenvalues from under-resolved "
                        "reparameterization modes: prefer gauge='normal')"
                        if gauge in ("comoving", "paper") else ""))
    method = "dense" if k is None else f"shift-invert (k={k}, sigma={sigma})"
    msg = (f"{MESSAGES[status]}; {gauge} gauge, {method} [{reported.method}]: "
           f"{vals.size} eigenvalues, {n_unstable} unstable, "
           f"{n_kernel} in the kernel (|lambda| <= {tol:.2e})")
    if cons:
        msg += ("; constrained (" + ", ".join(f"fixed {con.symbol}" for con in cons)
                + f"): {mc} normal direction(s) excluded")
    if check_reject:
        msg += f"; {spurious.size} rejected as spurious (N = {curve.N} vs {N2})"
    if notes:
        msg += "; " + "; ".join(notes)
    # the kernel is part of the small cluster: floor it at the smallest other |lambda|
    floor = float(np.min(np.abs(vals[~is_kernel]), initial=np.inf))
    floor = floor if np.isfinite(floor) else 0.0
    n_small, gap = small_cluster(vals, n_kernel, floor, max(2, curve.N // 4))
    return Spectrum(
        eigenvalues=vals, eigenvectors=reported.vectors, errors=err, is_kernel=is_kernel,
        unresolved=unresolved, unresolved_errors=unresolved_err, n_unstable=n_unstable,
        n_kernel=n_kernel, kernel_tol=float(tol), n_small=n_small, gap_ratio=gap, kernel=kr,
        spurious=spurious, drift=drift, gauge=gauge,
        method="dense" if k is None else "shift-invert", sigma=sigma, N=curve.N, N2=N2,
        roundoff=float(sol.roundoff) if np.isfinite(sol.roundoff) else _roundoff(op),
        max_imag=float(reported.max_imag),
        asymmetry=_asymmetry(op.H) if gauge == "normal" else np.nan,
        multipliers=LH.multipliers, projection_residual=LH.projection_residual,
        relative_residual=LH.relative_residual, rtol=rtol, success=status >= 0,
        status=status, message=msg, constraints=cons,
        constraint_multipliers=np.array(LH.constraint_multipliers, dtype=float))


def _roundoff(op, steps=15):
    """``eps |J|``, ``|J|`` by Lanczos with the factored product (``J`` is self-adjoint)."""
    return float(_EPS * lanczos_norm(op.matvec, None, op.w, steps))


def _asymmetry(H, probes=3):
    """``max |H x - H^T x| / |H x|`` over random probes: ``W J`` is symmetric iff ``H`` is."""
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(probes):
        x = rng.standard_normal(H.shape[0])
        a = H @ x
        b = H.T @ x
        worst = max(worst, np.linalg.norm(a - b) / max(np.linalg.norm(a), 1e-300))
    return float(worst)


def _failed(curve, LH, op, basis, gauge, k, sigma, rtol, exc) -> Spectrum:
    empty = np.array([])
    kr = build_kernel_report(curve, LH, op, basis, None, 0.0)
    return Spectrum(
        eigenvalues=empty, eigenvectors=np.zeros((curve.N, 0)), errors=empty,
        is_kernel=np.zeros(0, bool), unresolved=empty, unresolved_errors=empty, n_unstable=0,
        n_kernel=0, kernel_tol=0.0, n_small=0, gap_ratio=np.nan, kernel=kr, spurious=empty,
        drift=empty, gauge=gauge, method="dense" if k is None else "shift-invert", sigma=sigma,
        N=curve.N, N2=None, roundoff=np.nan, max_imag=np.nan, asymmetry=np.nan,
        multipliers=LH.multipliers, projection_residual=LH.projection_residual,
        relative_residual=LH.relative_residual, rtol=rtol, success=False, status=-1,
        message=f"{MESSAGES[-1]}: {exc}")
