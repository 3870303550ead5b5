"""Heteroclinic splices: quasi-equilibria made of 2N fronts (rounded polygons).

Section "Formal Equilibrium and Quasi-Steady Analysis" (e:psi_h and the 2N-front
quasi-equilibrium ``psi_N``, :mod:`qsa.equilibria.profile`: corner ``i`` is the arc
``[p_{2i-1}, p_{2i}]`` between an up-front and a down-front, the fronts cut off at a
fixed arc length).

Constraints and free parameters: the total turning ``kstar sum (p_{2i} - p_{2i-1}) =
2 pi`` (e:C2) and the closure ``int tau dsigma = 0`` (e:C1) are 3 equations for 2N
positions; a common shift of all positions only moves the base point, so
``2N - 4`` parameters are free. :func:`splice` moves the positions by minimum-norm
Gauss-Newton steps until ``|C| <= tol`` and returns a basis of the free directions.
Residuals (paper's ``R_kappa``, ``R_g``; ``L* = L`` balances the perimeter term): ::

    R_kappa = -alpha^2 psi_N'' + W'(psi_N),   R_g = -alpha^2/2 psi_N'^2 + W(psi_N).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from qsa._checks import finite_array, real_number
from qsa.curve import Curve
from qsa.discretize import Fourier
from qsa.energies import Faceting, Perimeter
from qsa.energies.wells import resolve_well
from qsa.equilibria.heteroclinic import heteroclinic
from qsa.equilibria.npulse import _grid, faceting_residual, resolving_size
from qsa.equilibria.profile import SpliceProfile
from qsa.equilibria.result import Equilibrium

__all__ = ["splice", "splice_polygon", "SpliceProfile", "polygon_positions", "splice_closure",
           "close_positions", "default_cutoff"]


def _fine_grid(front, L):
    M = int(8 * L / front.width) + 1
    M = max(M + (M + 1) % 2, 2049)
    return Fourier(M)


def _closure_and_jacobian(prof, fine, want_jac=True):
    L = prof.L
    sigma = L * fine.s
    psi = prof(sigma)
    theta = L * fine.cumulative(psi)
    e = np.exp(1j * theta)
    w = L * fine.weights
    C = np.array([np.real(e @ w), np.imag(e @ w), psi @ w - 2 * np.pi])
    if not want_jac:
        return C, None
    dpsi = prof.position_derivatives(sigma)  # (M, 2N)
    dtheta = L * fine.cumulative(dpsi)
    dC12 = (1j * e[:, None] * dtheta).T @ w
    J = np.vstack([dC12.real, dC12.imag, dpsi.T @ w])
    return C, J


def _check_positions(positions, L, cutoff, front):
    p = finite_array(positions, "positions")
    if p.ndim != 1 or p.size < 4 or p.size % 2:
        raise ValueError(f"positions must be 2N >= 4 front positions, got shape {p.shape}")
    if np.any(np.diff(p) <= 0) or p[-1] - p[0] >= L:
        raise ValueError("positions must increase strictly and span less than the length L")
    a_max = 0.5 * np.max(p[1::2] - p[0::2])
    if cutoff is None:  # margin: the closure solve may lengthen corners
        cutoff = default_cutoff(p, L)
    l1, l2 = (float(v) for v in cutoff)
    if not 0 < l1 < l2:
        raise ValueError(f"cutoff=(l1, l2) needs 0 < l1 < l2, got {cutoff!r}")
    if a_max + l2 > 0.5 * L + 1e-12 * L:
        raise ValueError(
            f"cutoff l2={l2} too long: a corner of half-length {a_max:.4g} plus l2 must not "
            f"exceed L/2={0.5 * L:.4g}"
        )
    return p, (l1, l2)


def default_cutoff(positions, length):
    """The default fixed cutoff ``(l1, l2)`` of :func:`splice` for these positions.

    ``l2 = 0.75 (L/2 - max a_i)`` (``a_i`` the corner half-lengths), ``l1 = l2 / 2``.

    Parameters
    ----------
    positions : array_like, shape (2N,)
        Front positions (see :func:`splice`).
    length : float
        Total length L.

    Returns
    -------
    (float, float)
        ``(l1, l2)``.

    Examples
    --------
    >>> import numpy as np
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> l1, l2 = default_cutoff(p, L)
    >>> bool(np.isclose(l2, 0.75 * (L / 2 - np.pi / 15))), bool(l1 == l2 / 2)
    (True, True)
    """
    p = np.asarray(positions, dtype=float)
    l2 = 0.75 * (0.5 * float(length) - 0.5 * np.max(p[1::2] - p[0::2]))
    return (0.5 * l2, l2)


def splice_closure(profile, grid=None, jacobian=True):
    """Closure defect ``C(p)`` of a splice and its derivative in the positions.

    Parameters
    ----------
    profile : SpliceProfile
    grid : Fourier, optional
        Quadrature grid on ``[0, 1)`` (``sigma = L s``); default a grid with about
        eight points per front width.
    jacobian : bool

    Returns
    -------
    C : ndarray, shape (3,)
        ``(int cos theta dsigma, int sin theta dsigma, int psi_N dsigma - 2 pi)``
        (e:C1, e:C2), ``theta(0) = 0``.
    J : ndarray, shape (3, 2N) or None
        ``dC/dp``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import heteroclinic
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> prof = SpliceProfile(heteroclinic(0.2, kstar=5.0), p, L, default_cutoff(p, L))
    >>> C, J = splice_closure(prof)  # symmetric triangle: closed by symmetry
    >>> bool(np.linalg.norm(C) < 1e-12), J.shape
    (True, (3, 6))
    """
    fine = _fine_grid(profile.front, profile.L) if grid is None else grid
    return _closure_and_jacobian(profile, fine, want_jac=jacobian)


def close_positions(positions, front, length, cutoff, tol=1e-12, max_iter=30):
    """Minimum-norm Gauss-Newton steps on the positions until ``|C(p)| <= tol``.

    Parameters
    ----------
    positions : array_like, shape (2N,)
    front : Heteroclinic
    length : float
    cutoff : (float, float)
    tol : float
    max_iter : int

    Returns
    -------
    positions : ndarray, shape (2N,)
    history : list of float
        ``|C|`` before each step and after the last.
    J : ndarray, shape (3, 2N)
        ``dC/dp`` at the returned positions.

    Raises
    ------
    ValueError
        Bad positions or cutoff, or a solve that makes fronts cross.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import heteroclinic
    >>> p, L = polygon_positions(np.radians([90, 90, 90, 90]), [1.0, 1.2, 1.0, 1.2], 5.0)
    >>> front = heteroclinic(0.2, kstar=5.0)
    >>> q, history, J = close_positions(p, front, L, default_cutoff(p, L))
    >>> bool(history[-1] < 1e-12), q.shape, J.shape
    (True, (8,), (3, 8))
    """
    L = real_number(length, "length", positive=True)
    p, cut = _check_positions(positions, L, cutoff, front)
    fine = _fine_grid(front, L)
    C, J = _closure_and_jacobian(SpliceProfile(front, p, L, cut), fine)
    history = [float(np.linalg.norm(C))]
    it = 0
    while history[-1] > tol and it < max_iter:
        p = p + np.linalg.lstsq(J, -C, rcond=None)[0]
        it += 1
        if np.any(np.diff(p) <= 0):
            raise ValueError(
                "the splice cannot close: the closure solve makes fronts cross (corners or "
                "facets of non-positive length); start from positions nearer a closed polygon"
            )
        C, J = _closure_and_jacobian(SpliceProfile(front, p, L, cut), fine)
        history.append(float(np.linalg.norm(C)))
    return p, history, J


def _null_directions(J, n):
    A = np.vstack([J, np.ones((1, n)) / np.sqrt(n)])
    _, sv, Vt = np.linalg.svd(A)
    return Vt[4:]  # (2N - 4, 2N): orthonormal, orthogonal to shifts, tangent to C = 0


def splice(positions, alpha, well=None, grid=None, length=None, kstar=None, beta=5.0,
           cutoff=None, solve=True, tol=1e-12, max_iter=30):
    """The 2N-front splice ``psi_N`` from front positions, closed to ``tol``.

    Parameters
    ----------
    positions : array_like, shape (2N,)
        Arc-length positions of the fronts, increasing, up-front first: corner ``i``
        is ``[p_{2i-1}, p_{2i}]``.
    alpha : float
        ``> 0``.
    well, kstar
        As in :func:`heteroclinic`.
    grid : Grid, int or None
        Grid of the returned curve (``None``: a Fourier grid resolving the fronts).
    length : float
        Total length ``L`` (required).
    beta : float
        Perimeter penalty; ``L* = L`` balances it (``R_g`` has no perimeter term).
    cutoff : (float, float), optional
        Fixed arc lengths ``(l1, l2)`` of the front cutoff; default the largest
        ``l2 = 0.75 (L/2 - max a_i)`` (a_i the corner half-lengths) and ``l1 = l2 / 2``.
    solve : bool
        Move the positions (minimum-norm Gauss-Newton) until ``|C| <= tol``.

    Returns
    -------
    Equilibrium
        ``kind="splice"``; ``params`` with ``positions`` (solved), ``L``, ``L_star``,
        ``nu1 = nu2 = 0``, ``d_min``, ``cutoff``; ``extra`` with ``R_kappa``, ``R_g``
        (at the nodes), ``free_directions`` (shape (2N - 4, 2N)), ``profile``
        (:class:`SpliceProfile`), ``iterations``. ``success`` means closure reached.

    Raises
    ------
    ValueError
        Bad positions, length, cutoff or alpha.

    Examples
    --------
    >>> import numpy as np
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> eq = splice(p, 0.2, kstar=5.0, length=L)
    >>> eq.kind, bool(eq.success), bool(eq.closure < 1e-12), eq.params["n_corners"]
    ('splice', True, True, 3)
    """
    alpha = real_number(alpha, "alpha", positive=True)
    beta = real_number(beta, "beta", positive=True)
    if length is None:
        raise ValueError("length (the total arc length L) is required")
    L = real_number(length, "length", positive=True)
    well, kstar = resolve_well(well, kstar)
    front = heteroclinic(alpha, well, kstar)
    p, cut = _check_positions(positions, L, cutoff, front)
    p, history, J = close_positions(p, front, L, cut, tol, max_iter if solve else 0)
    it = len(history) - 1
    p, cut = _check_positions(p, L, cut, front)
    prof = SpliceProfile(front, p, L, cut)

    def kappa_of_s(s):
        return prof(L * np.asarray(s))

    grid = _grid(grid, kappa_of_s) if grid is not None else Fourier(resolving_size(kappa_of_s))
    base = Curve(kappa_of_s(grid.s), L, grid)
    centre = (base.positions() @ base.dsigma) / L
    curve = Curve(base.kappa, L, grid, 0.0, tuple(-centre))
    energy = Faceting(alpha, kstar, well) + Perimeter(beta, L)
    R_kappa, R_g = prof.residuals(L * grid.s)
    res, scale = faceting_residual(energy, curve, alpha, well)
    closure = float(np.linalg.norm(curve.closure()))
    gaps = np.diff(np.append(p, p[0] + L))
    ok = history[-1] <= tol
    msg = (f"splice: closure {history[-1]:.1e} after {it} Gauss-Newton steps; "
           f"max|R_kappa| = {np.max(np.abs(R_kappa)):.2e}, max|V^n| = {res:.2e}")
    if not ok:
        msg += f"; closure above tol={tol}"
    params = {"nu1": 0.0, "nu2": 0.0, "L": L, "L_star": L, "alpha": alpha, "beta": beta,
              "kstar": kstar, "positions": p.tolist(), "d_min": float(gaps.min()),
              "cutoff": list(cut), "n_corners": p.size // 2}
    extra = {"R_kappa": R_kappa, "R_g": R_g, "free_directions": _null_directions(J, p.size),
             "profile": prof, "iterations": it, "closure_history": history}
    return Equilibrium(curve, energy, params, np.zeros(3), res, closure, scale, "splice", ok,
                       msg, extra)


def polygon_positions(angles, facets, kstar):
    """Front positions of the sharp rounded polygon with these corners and facets.

    Corner ``i`` (exterior angle ``angles[i]``) is an arc of curvature ``kstar`` and
    length ``angles[i] / kstar``; it is followed by the straight facet ``facets[i]``.
    ``s = 0`` is the middle of the last facet.

    Returns
    -------
    positions : ndarray, shape (2N,)
    length : float

    Raises
    ------
    ValueError
        Angles not positive or not summing to 2 pi, facets not positive, or the
        sharp polygon far from closing (its closure defect is reported).

    Parameters
    ----------
    angles : array_like, shape (N,)
        Exterior corner angles, positive, summing to ``2 pi``.
    facets : array_like, shape (N,)
        Facet lengths, positive.
    kstar : float
        Curvature of the corner arcs.

    Examples
    --------
    >>> import numpy as np
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> p.shape, bool(np.isclose(L, 3.0 + 2 * np.pi / 5.0))
    ((6,), True)
    >>> np.round(np.diff(p), 10).tolist()  # arc, facet, arc, facet, arc
    [0.4188790205, 1.0, 0.4188790205, 1.0, 0.4188790205]
    """
    ang = finite_array(angles, "angles")
    fac = finite_array(facets, "facets")
    if ang.ndim != 1 or ang.size < 2 or fac.shape != ang.shape:
        raise ValueError("angles and facets must be 1-d arrays of the same length N >= 2")
    if np.any(ang <= 0):
        raise ValueError("angles must be positive (corners turn towards kstar > 0)")
    if abs(ang.sum() - 2 * np.pi) > 1e-9:
        raise ValueError(f"angles must sum to 2 pi (a closed curve), got {ang.sum()!r}")
    if np.any(fac <= 0):
        raise ValueError("facets must have positive lengths")
    arcs = ang / kstar
    pos, s = [], 0.5 * fac[-1]  # s = 0 in the middle of the last facet
    for arc, f in zip(arcs, fac, strict=True):
        pos += [s, s + arc]
        s += arc + f
    return np.array(pos), s - 0.5 * fac[-1]


def _sharp_facets(arcs, angles, facets, kstar):
    """Minimum-norm change of the facets that closes the sharp rounded polygon.

    Corner i turns from direction ``phi_i`` by ``angles[i]`` along an arc of radius
    ``1/kstar``; facet i then runs in direction ``phi_{i+1}``. Closure is linear in
    the facets: ``sum f_i e^{i phi_{i+1}} = -sum chord_i``.
    """
    phi = np.concatenate([[0.0], np.cumsum(angles)])
    chords = (np.exp(1j * phi[1:]) - np.exp(1j * phi[:-1])) / (1j * kstar)
    A = np.vstack([np.cos(phi[1:]), np.sin(phi[1:])])
    rhs = -np.array([chords.sum().real, chords.sum().imag]) - A @ facets
    return facets + np.linalg.lstsq(A, rhs, rcond=None)[0]


def splice_polygon(angles, facets, alpha, well=None, grid=None, kstar=None, tol=1e-12,
                   max_iter=30, **kwargs):
    """A splice shaped like a rounded polygon with the given corner angles.

    Corner ``i`` turns by ``angles[i]`` (an arc of curvature ``kstar`` between an up- and
    a down-front) and is followed by a facet of length close to ``facets[i]``. The
    angles are kept; the facets are changed by the smallest amount (least squares)
    that closes the curve -- first for sharp fronts (a linear problem), then with the
    real fronts by Gauss-Newton steps in the facet lengths.

    Parameters
    ----------
    angles : array_like, shape (N,)
        Exterior corner angles, positive, summing to ``2 pi``.
    facets : array_like, shape (N,)
        Requested facet lengths, positive.
    alpha, well, grid, kstar, tol, max_iter
        As in :func:`splice`; further keyword arguments are passed on to it.

    Raises
    ------
    ValueError
        Invalid polygon data (see :func:`polygon_positions`), or a polygon that cannot
        close with these angles and facets longer than two front widths (e.g. two
        corners that are not both ``pi``).

    Returns
    -------
    Equilibrium
        As :func:`splice` (a quasi-equilibrium: ``residual`` exponentially small in
        ``kstar d_min / alpha``), with ``params["angles"]``, ``params["facets"]`` (the
        closing facet lengths) and ``params["d_min"]``.

    Examples
    --------
    >>> import numpy as np
    >>> eq = splice_polygon(np.radians([120, 120, 120]), [1.0, 1.3, 1.0], 0.2, kstar=5.0)
    >>> bool(eq.success), bool(eq.closure < 1e-12), round(eq.params["d_min"], 6)
    (True, True, 0.418879)
    """
    well, kstar = resolve_well(well, kstar)
    alpha = real_number(alpha, "alpha", positive=True)
    positions, _ = polygon_positions(angles, facets, kstar)
    ang = np.asarray(angles, dtype=float)
    arcs = ang / kstar
    f = _sharp_facets(arcs, ang, np.asarray(facets, dtype=float), kstar)

    def cannot_close(f):
        raise ValueError(
            f"the polygon cannot close with angles {np.round(ang, 6).tolist()}: closing it "
            f"needs facet lengths {np.round(f, 6).tolist()}, not all longer than two front "
            f"widths ({2 * front.width:.3g})"
        )

    front = heteroclinic(alpha, well, kstar)
    if np.any(f <= 2 * front.width):
        cannot_close(f)
    cutoff = kwargs.pop("cutoff", None)

    def closure(f):
        p, L = polygon_positions(ang, f, kstar)
        p, cut = _check_positions(p, L, cutoff, front)
        C, _ = _closure_and_jacobian(SpliceProfile(front, p, L, cut), _fine_grid(front, L),
                                     want_jac=False)
        return C[:2]

    C = closure(f)
    for _ in range(max_iter):
        if np.linalg.norm(C) <= 0.1 * tol:
            break
        h = 1e-7 * np.max(f)
        J = np.column_stack([(closure(f + h * e) - closure(f - h * e)) / (2 * h)
                             for e in np.eye(f.size)])
        f = f + np.linalg.lstsq(J, -C, rcond=None)[0]
        if np.any(f <= 2 * front.width):
            cannot_close(f)
        C = closure(f)
    positions, L = polygon_positions(ang, f, kstar)
    eq = splice(positions, alpha, well, grid, length=L, kstar=kstar, tol=tol,
                max_iter=max_iter, cutoff=cutoff, **kwargs)
    return replace(eq, params={**eq.params, "angles": ang.tolist(), "facets": f.tolist()})
