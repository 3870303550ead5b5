"""Near-contact spacing of polished folded CHA equilibria as ``l* -> 0`` (s:NSI).

The paper's near-contact analysis predicts that two anti-parallel sheets of a
curve paired by the adhesion kernel settle at the separation
``d* = l* sqrt(a^2 + 1/2)`` (:attr:`~qsa.energies.AdhesionKernel.pair_separation`)
up to corrections of relative size ``O(eps |kappa|_H2, l*)`` that vanish as the
screening length ``l*`` shrinks. This module measures it on real equilibria:

* :func:`dumbbell` -- a closed curve of arcs and segments: two lobes joined by a
  neck of two parallel sheets (a zipped fold whose sheets turn apart into the
  lobes with bounded curvature, no hairpin);
* :func:`paired_dumbbell` -- a short CHA flow from it, polished by Newton's method
  on a Fourier grid (:func:`qsa.paper.folded.folded_equilibrium`);
* :func:`near_contact_sweep` -- natural continuation of such an equilibrium in
  ``l*`` (the perimeter target and the other parameters fixed), refining the grid
  so the sheets keep ``nodes_per_l_star`` nodes per ``l*``, and at each requested
  ``l*`` the spacing at the middle of the paired sheets
  (:func:`qsa.flows.analysis.paired_sheets`) against ``d*``, its grid check on
  ``Fourier(2N - 1)``, and the order fitted to the relative errors;
* :func:`relaxation_length` and :func:`decay_length` -- how fast the spacing
  settles to ``d*`` along a pair, predicted and measured.

Along a straight pair the deviation ``eta(s)`` of each sheet from ``d*/2`` off the
midline obeys, linearized, ``eps d^4 eta / ds^4 + 2 k eta = 0`` (bending against the
adhesion force, whose derivative in the spacing at ``d*`` is the stiffness ``k``,
:func:`pair_stiffness`; tension and the width ``l*`` of the kernel neglected): the
spacing relaxes from the ends of the pair in oscillations decaying on the length
``sqrt(2) (eps / (2 k))^(1/4)``, which shrinks like ``l*^(1/4)``. In the middle of a
long pair what is left of ``d* - spacing`` is exponentially small.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa import Fourier
from qsa._checks import real_number
from qsa.energies import AdhesionKernel
from qsa.flows import CHA, solve_flow
from qsa.flows.analysis import paired_sheets
from qsa.paper.folded import folded_equilibrium

__all__ = ["dumbbell", "paired_dumbbell", "SpacingPoint", "NearContactSweep",
           "near_contact_sweep", "near_contact_study", "sheet_spacing", "pair_stiffness",
           "relaxation_length", "decay_length"]

#: Table T1's parameters besides ``l*`` (Canham-Helfrich, perimeter, adhesion).
T1 = {"eps": 0.08, "beta": 60.0, "A0": 40.0, "a": 1.0}
_PARAMS = ("eps", "beta", "A0", "a", "L_star")


def dumbbell(neck, spacing, radius, fillet, N):
    """Nodes of a dumbbell: two lobes joined by a neck of two parallel sheets.

    The curve is made of segments and circular arcs with a continuous tangent:
    the lower sheet (``y = -spacing/2``, length ``neck``, along ``+x``), a lobe (an
    arc of radius ``fillet`` turning right, one of radius ``R`` turning left, one
    of radius ``fillet`` turning right), the upper sheet back, and the mirror
    lobe. ``R`` is the lobe radius that closes the curve with the lobe's centre on
    the neck's axis; it is ``radius`` within the fillet's geometry, see below.

    Parameters
    ----------
    neck : float
        Length of the sheets.
    spacing : float
        Distance between the sheets.
    radius : float
        Radius of the lobes' large arcs (the fillet angle is chosen to close the
        curve, so ``radius > spacing / 2``).
    fillet : float
        Radius of the arcs joining the sheets to the lobes.
    N : int
        Number of nodes, equally spaced in arc length (counter-clockwise, the first
        at the start of the lower sheet).

    Returns
    -------
    x, y : ndarray, shape (N,)
    """
    neck = real_number(neck, "neck", positive=True)
    spacing = real_number(spacing, "spacing", positive=True)
    radius = real_number(radius, "radius", positive=True)
    fillet = real_number(fillet, "fillet", positive=True)
    if not radius > spacing / 2:
        raise ValueError(f"radius: need more than spacing / 2 = {spacing / 2:g}, got {radius:g}")
    if int(N) != N or N < 8:
        raise ValueError(f"N: need an integer >= 8, got {N!r}")
    # the large arc's centre is on the axis: R cos(phi) = spacing/2 + fillet (1 - cos(phi))
    phi = float(np.arccos((spacing / 2 + fillet) / (radius + fillet)))
    lobe = [(fillet * phi, -1 / fillet), (radius * (np.pi + 2 * phi), 1 / radius),
            (fillet * phi, -1 / fillet)]
    pieces = [(neck, 0.0), *lobe, (neck, 0.0), *lobe]
    lengths = np.array([p[0] for p in pieces])
    starts = np.concatenate([[0.0], np.cumsum(lengths)])
    s = np.arange(int(N)) * starts[-1] / int(N)
    point, angle = np.array([-neck / 2, -spacing / 2]), 0.0
    x, y = np.empty(int(N)), np.empty(int(N))
    for (length, k), s0, s1 in zip(pieces, starts[:-1], starts[1:], strict=True):
        on = (s >= s0) & (s < s1)
        u = s[on] - s0
        x[on], y[on] = _advance(point, angle, k, u)
        point = np.array(_advance(point, angle, k, np.array([length]))).ravel()
        angle += k * length
    return x, y


def _advance(point, angle, k, u):
    """Positions at arc length ``u`` along a piece of curvature ``k`` from ``point``."""
    if k == 0:
        return point[0] + u * np.cos(angle), point[1] + u * np.sin(angle)
    return (point[0] + (np.sin(angle + k * u) - np.sin(angle)) / k,
            point[1] - (np.cos(angle + k * u) - np.cos(angle)) / k)


def paired_dumbbell(l_star, *, eps=T1["eps"], beta=T1["beta"], A0=T1["A0"], a=T1["a"],
                    neck=2.0, radius=0.25, fillet=0.05, N=601, t_flow=1.0, tol=1e-10):
    """A polished folded CHA equilibrium with one long pair of sheets (a zipped dumbbell).

    The :func:`dumbbell` with sheets ``d* = l* sqrt(a^2 + 1/2)`` apart relaxes by the
    CHA flow (finite differences, ``N`` nodes, the perimeter target its initial
    length) for ``t_flow``; the final state is polished on ``Fourier(N)`` (``N`` made
    odd) by :func:`~qsa.paper.folded.folded_equilibrium` without its spectrum.

    Parameters
    ----------
    l_star : float
        Screening length.
    eps, beta, A0, a : float
        CHA parameters (default Table T1's).
    neck, radius, fillet : float
        Geometry of the initial :func:`dumbbell`.
    N : int
        Nodes of the flow and of the polish.
    t_flow : float
        Duration of the relaxing flow.
    tol : float
        Relative residual of the polish.

    Returns
    -------
    FoldedEquilibrium
        ``params["L_star"]`` is the perimeter target (the dumbbell's length);
        ``polished.success`` says whether the polish converged (from the flow's last
        state, also when the flow stopped before ``t_flow``).
    """
    l_star = real_number(l_star, "l_star", positive=True)
    d = AdhesionKernel(A0, l_star, a).pair_separation
    x, y = dumbbell(neck, d, radius, fillet, N)
    L0 = float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))
    res = solve_flow(CHA(eps=eps, beta=beta, rho=1.0, A0=A0, l_star=l_star, a=a), (x, y),
                     t_flow, N=N, tol=1e-5, method="bdf2", t_eval=[t_flow], progress=False)
    # a flow that stopped early leaves its last state to the polish, which says if it fails
    return folded_equilibrium(res.x, res.y, eps=eps, beta=beta, rho=1.0, L0=L0, A0=A0,
                              l_star=l_star, a=a, name=f"dumbbell l*={l_star:g}", tol=tol,
                              with_spectrum=False, rate_check=False)


def sheet_spacing(curve, l_star, a=1.0, A0=1.0):
    """The paired sheets of ``curve`` measured against ``d* = l* sqrt(a^2 + 1/2)``.

    Returns the :class:`~qsa.flows.analysis.SheetPairs` of the curve's nodes
    (``target = d*``); ``mid_separations`` is the spacing at the middle of each pair.
    """
    x, y = curve.positions()
    return paired_sheets(x, y, AdhesionKernel(A0, l_star, a).pair_separation)


def pair_stiffness(A0, l_star, a=1.0):
    """Derivative in the spacing of the normal adhesion force between straight strands, at ``d*``.

    The force on one strand from the other, ``D = d~ l*`` apart, has the normal component
    ``4 sqrt(pi) (A0 / a^2) d~ exp(-d~^2) (d~^2 - a^2 - 1/2)`` (Conventions and errata,
    section 6); at ``d~*^2 = a^2 + 1/2`` its derivative in ``D`` is
    ``k = 8 sqrt(pi) A0 d~*^2 exp(-d~*^2) / (a^2 l*)``.
    """
    kern = AdhesionKernel(A0, l_star, a)
    d2 = (kern.pair_separation / kern.l_star) ** 2
    return float(8 * np.sqrt(np.pi) * kern.A0 * d2 * np.exp(-d2) / (kern.a ** 2 * kern.l_star))


def relaxation_length(eps, A0, l_star, a=1.0):
    """Decay length of the spacing's deviation from ``d*`` along a straight pair of sheets.

    ``sqrt(2) (eps / (2 k))^(1/4)`` with ``k`` the :func:`pair_stiffness`: one over the
    real part of the roots of ``lambda^4 = -2 k / eps`` (see the module docstring). The
    deviation oscillates with wavelength ``2 pi`` times this length.
    """
    eps = real_number(eps, "eps", positive=True)
    return float(np.sqrt(2.0) * (eps / (2 * pair_stiffness(A0, l_star, a))) ** 0.25)


def decay_length(arc, spacing, target, floor=1e-8, ceiling=1e-2):
    """Measured decay length of ``|spacing / target - 1|`` from the ends of a pair inward.

    In each half of the pair (from an end to the middle) the local maxima of the
    relative deviation between ``floor`` and ``ceiling`` are fitted by
    ``log r = c - x / length`` in the distance ``x`` from that end; the result is the mean
    over the halves with at least two maxima (``nan`` without).

    Parameters
    ----------
    arc, spacing : array_like
        A pair's profile (:attr:`qsa.flows.analysis.SheetPairs.profiles`).
    target : float
        ``d*``.
    floor, ceiling : float
        Range of relative deviations fitted: above the measurement's precision,
        below the nonlinear turning regions.

    Returns
    -------
    float
    """
    arc, spacing = np.asarray(arc, float), np.asarray(spacing, float)
    r = np.abs(spacing / float(target) - 1)
    mid = arc[-1] / 2
    lengths = []
    for half in (arc <= mid, arc > mid):
        x = np.where(arc <= mid, arc, arc[-1] - arc)[half]
        rr = r[half]
        peak = np.flatnonzero((rr[1:-1] >= rr[:-2]) & (rr[1:-1] >= rr[2:])
                              & (rr[1:-1] > floor) & (rr[1:-1] < ceiling)) + 1
        if peak.size >= 2:
            slope = np.polyfit(x[peak], np.log(rr[peak]), 1)[0]
            if slope < 0:
                lengths.append(-1.0 / slope)
    return float(np.mean(lengths)) if lengths else float("nan")


@dataclass(frozen=True)
class SpacingPoint:
    """The spacing of the paired sheets of one polished equilibrium.

    Attributes
    ----------
    l_star : float
    N : int
        Nodes of the Fourier grid.
    relative_residual : float
        Of the Newton polish (``max|V^n|`` over the largest term, or the closure).
    success : bool
        The polish converged to ``tol``.
    spacing : float
        Separation at the middle of the longest pair (``nan`` without pairs).
    target : float
        ``d* = l* sqrt(a^2 + 1/2)``.
    median, minimum : float
        Median and smallest separation of that pair (the minimum sits where the
        sheets turn apart).
    pair_length : float
        Arc length of the pair.
    n_pairs : int
    decay : float
        :func:`decay_length` of the pair's profile (``nan`` when it has too few maxima).
    predicted_decay : float
        :func:`relaxation_length`.
    refined_spacing : float or None
        The mid spacing of the same equilibrium polished on ``Fourier(2N - 1)``.
    """

    l_star: float
    N: int
    relative_residual: float
    success: bool
    spacing: float
    target: float
    median: float
    minimum: float
    pair_length: float
    n_pairs: int
    decay: float = float("nan")
    predicted_decay: float = float("nan")
    refined_spacing: float | None = None

    @property
    def relative_error(self) -> float:
        """``spacing / d* - 1``."""
        return float(self.spacing / self.target - 1)

    @property
    def decay_error(self) -> float:
        """``decay / predicted_decay - 1``: how well the linearized balance predicts the tail."""
        return float(self.decay / self.predicted_decay - 1)

    @property
    def grid_change(self) -> float | None:
        """``|refined_spacing - spacing| / d*`` (``None`` without the refined grid)."""
        if self.refined_spacing is None:
            return None
        return float(abs(self.refined_spacing - self.spacing) / self.target)

    def to_dict(self) -> dict:
        return {"l_star": self.l_star, "N": self.N,
                "relative_residual": self.relative_residual, "success": self.success,
                "spacing": self.spacing, "target": self.target,
                "relative_error": self.relative_error, "median": self.median,
                "minimum": self.minimum, "pair_length": self.pair_length,
                "n_pairs": self.n_pairs, "decay_length": self.decay,
                "predicted_decay_length": self.predicted_decay,
                "decay_error": self.decay_error,
                "refined_spacing": self.refined_spacing,
                "grid_change": self.grid_change}


@dataclass(frozen=True)
class NearContactSweep:
    """Mid spacings of the paired sheets along a branch in ``l*`` (:func:`near_contact_sweep`).

    Attributes
    ----------
    points : tuple of SpacingPoint
        One per requested ``l*``, in the order reached.
    params : dict
        ``eps, beta, A0, a, L_star``.
    order : float
        Slope of ``log|relative_error|`` against ``log l*`` (least squares over the
        points; ``nan`` with fewer than two). The errors in the middle of a pair are
        the tails of its ends, so this is a summary, not the order of a power law.
    curves : tuple of Curve
        The polished equilibria (not in the summary).
    success : bool
        Every polish converged and every point has a pair of sheets.
    message : str
    """

    points: tuple
    params: dict
    order: float
    curves: tuple = field(default=(), repr=False)
    success: bool = True
    message: str = ""

    @property
    def decay_order(self) -> float:
        """Slope of ``log|decay_error|`` against ``log l*`` (least squares; ``nan`` with
        fewer than two finite values)."""
        return _fitted_order([p.l_star for p in self.points],
                             [p.decay_error for p in self.points])

    def profiles(self) -> list:
        """``(arc, spacing)`` along the longest pair of each curve (``None`` without pairs).

        See :attr:`qsa.flows.analysis.SheetPairs.profiles`.
        """
        out = []
        for p, c in zip(self.points, self.curves, strict=True):
            sp = sheet_spacing(c, p.l_star, self.params["a"], self.params["A0"])
            out.append(sp.profiles[int(np.argmax(sp.lengths))] if sp.n_pairs else None)
        return out

    def summary(self) -> dict:
        """JSON-able summary."""
        return {"params": dict(self.params), "order": self.order,
                "decay_order": self.decay_order, "success": self.success,
                "message": self.message, "points": [p.to_dict() for p in self.points]}

    def table(self) -> str:
        """The points as a Markdown table."""
        rows = ["| l* | N | relative residual | mid spacing | d* | spacing/d* - 1 "
                "| N -> 2N-1 change / d* | pair length | decay length | predicted |",
                "|---|---|---|---|---|---|---|---|---|---|"]
        for p in self.points:
            change = "" if p.grid_change is None else f"{p.grid_change:.1e}"
            rows.append(f"| {p.l_star:g} | {p.N} | {p.relative_residual:.1e} "
                        f"| {p.spacing:.10f} | {p.target:.10f} | {p.relative_error:+.3e} "
                        f"| {change} | {p.pair_length:.3f} | {p.decay:.4f} "
                        f"| {p.predicted_decay:.4f} |")
        return "\n".join(rows)


def _fitted_order(l_stars, errors):
    """Least-squares slope of ``log|error|`` against ``log l*`` (``nan`` below two points)."""
    ls, err = np.asarray(l_stars, float), np.abs(np.asarray(errors, float))
    good = np.isfinite(err) & (err > 0)
    if good.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(ls[good]), np.log(err[good]), 1)[0])


def _grid_size(length, l_star, nodes_per_l_star, N_min):
    N = max(int(N_min), int(np.ceil(nodes_per_l_star * length / l_star)))
    return N + 1 - N % 2


def _polish(curve, l_star, params, N, tol):
    """:func:`folded_equilibrium` of ``curve`` on ``Fourier(N)`` at screening length ``l_star``."""
    p = params
    guess = curve if curve.N == N else curve.on_grid(Fourier(N))
    return folded_equilibrium(guess, None, eps=p["eps"], beta=p["beta"], rho=1.0,
                              L0=p["L_star"], A0=p["A0"], l_star=l_star, a=p["a"],
                              tol=tol, with_spectrum=False, rate_check=False, resolve=None)


def _point(fe, l_star, params, refined=None):
    sp = sheet_spacing(fe.curve, l_star, params["a"], params["A0"])
    if sp.n_pairs:
        i = int(np.argmax(sp.lengths))
        mid, med, lo, ln = (sp.mid_separations[i], sp.separations[i], sp.min_separations[i],
                            sp.lengths[i])
        decay = decay_length(*sp.profiles[i], sp.target)
    else:
        mid = med = lo = ln = decay = float("nan")
    return SpacingPoint(l_star=float(l_star), N=int(fe.N),
                        relative_residual=fe.relative_residual,
                        success=bool(fe.polished.success), spacing=float(mid),
                        target=float(sp.target), median=float(med), minimum=float(lo),
                        pair_length=float(ln), n_pairs=int(sp.n_pairs), decay=decay,
                        predicted_decay=relaxation_length(params["eps"], params["A0"], l_star,
                                                          params["a"]),
                        refined_spacing=refined)


def near_contact_sweep(start, l_stars, *, nodes_per_l_star=10.0, max_ratio=2 ** 0.25,
                       N_min=301, tol=1e-10, check_grid=True, progress=None):
    """Follow a folded equilibrium in ``l*`` and measure the spacing of its paired sheets.

    Natural continuation: from ``start`` (a polished :class:`FoldedEquilibrium`,
    e.g. :func:`paired_dumbbell`) the screening length moves to each value of
    ``l_stars`` in turn in geometric steps of ratio at most ``max_ratio``, the
    previous equilibrium (resampled spectrally) being the Newton guess of the next;
    the other parameters, the perimeter target included, stay fixed. The grid is
    ``Fourier(N)`` with ``N`` the odd number giving ``nodes_per_l_star`` nodes per
    ``l*`` along the curve (at least ``N_min``). At each requested ``l*`` the spacing
    at the middle of the longest pair of sheets is compared with ``d*``; with
    ``check_grid`` the state is also polished on ``Fourier(2N - 1)`` and measured
    again.

    Parameters
    ----------
    start : FoldedEquilibrium
        A polished equilibrium (its ``params`` give ``eps, beta, A0, a, L_star`` and
        the starting ``l*``).
    l_stars : sequence of float
        Screening lengths at which to measure, in the order to visit them.
    nodes_per_l_star : float
        Resolution of the paired sheets.
    max_ratio : float
        Largest ratio between consecutive screening lengths of the continuation.
    N_min : int
        Smallest grid.
    tol : float
        Relative residual of every polish.
    check_grid : bool
        Measure again on the refined grid.
    progress : callable, optional
        Called with a line of text after each requested ``l*``.

    Returns
    -------
    NearContactSweep
        Stops at the first failed polish (``success=False``, the points measured so
        far, the message naming the screening length).
    """
    if not (start.polished.success):
        raise ValueError("start: the starting equilibrium is not polished (success=False)")
    l_stars = [real_number(v, "l_stars", positive=True) for v in l_stars]
    if not l_stars:
        raise ValueError("l_stars: need at least one screening length")
    if not max_ratio > 1:
        raise ValueError(f"max_ratio: need > 1, got {max_ratio!r}")
    p = start.params
    params = {k: float(p[k]) for k in _PARAMS}
    curve, current = start.curve, float(p["l_star"])
    points, curves, message = [], [], "all polishes converged"
    for target in l_stars:
        n_steps = max(1, int(np.ceil(abs(np.log(target / current)) / np.log(max_ratio) - 1e-9)))
        ok = True
        for ls in current * (target / current) ** (np.arange(1, n_steps + 1) / n_steps):
            N = _grid_size(curve.length(), ls, nodes_per_l_star, N_min)
            fe = _polish(curve, ls, params, N, tol)
            if not fe.polished.success:
                ok = False
                message = f"the polish failed at l* = {ls:.6g} (N = {N}): {fe.polished.message}"
                break
            curve = fe.curve
        if not ok:
            break
        current = target
        refined = None
        if check_grid:
            fine = _polish(curve, target, params, 2 * curve.N - 1, tol)
            refined = _point(fine, target, params).spacing if fine.polished.success else None
        pt = _point(fe, target, params, refined)
        points.append(pt)
        curves.append(curve)
        if progress is not None:
            progress(f"l* = {target:g}: N = {pt.N}, relative residual "
                     f"{pt.relative_residual:.1e}, spacing/d* - 1 = {pt.relative_error:+.3e}")
    order = _fitted_order([pt.l_star for pt in points], [pt.relative_error for pt in points])
    success = (len(points) == len(l_stars) and all(pt.success and pt.n_pairs for pt in points))
    return NearContactSweep(points=tuple(points), params=params, order=order,
                            curves=tuple(curves), success=success, message=message)


def near_contact_study(l_stars=(0.2, 0.1, 0.05, 0.025), *, start_l_star=0.05,
                       nodes_per_l_star=10.0, check_grid=True, progress=None, **params):
    """The documented sweep: a dumbbell polished at ``start_l_star``, followed in ``l*``.

    :func:`paired_dumbbell` at ``start_l_star``, then :func:`near_contact_sweep` through
    ``l_stars``. ``params`` go to :func:`paired_dumbbell` (``eps, beta, A0, a``, the
    geometry, ``N``, ``t_flow``); the defaults are Table T1's parameters and the dumbbell
    of the documentation (perimeter target 7.13, a pair of sheets 2.6 long at
    ``l* = 0.05``). Takes about six minutes with the grid checks, mostly at
    ``l* = 0.025``. A starting dumbbell that does not polish gives a sweep without
    points, ``success=False``.
    """
    start = paired_dumbbell(start_l_star, **params)
    if not start.polished.success:
        p = start.params
        return NearContactSweep(points=(), params={k: float(p[k]) for k in _PARAMS},
                                order=float("nan"), success=False,
                                message=f"the starting dumbbell at l* = {start_l_star:g} did "
                                        f"not polish: {start.polished.message}")
    return near_contact_sweep(start, l_stars, nodes_per_l_star=nodes_per_l_star,
                              check_grid=check_grid, progress=progress)
