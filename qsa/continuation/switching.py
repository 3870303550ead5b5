"""Branch switching at a located bifurcation: one new branch per symmetry-distinct direction.

At a branch point with critical normal mode ``phi`` the bifurcating equilibria leave
the old branch tangentially to the state perturbation ``M(phi, 0) = (G phi, g kappa phi)``
(``G = -Delta_s - kappa^2``; in the constant-``g`` layout of the continuation:
``d kappa = G phi``, ``d L = <kappa, phi>``, ``d p = 0``). The first point of the new
branch solves ``F(x, p) = 0`` on the hyperplane ``<y - y* - eps d, d>_w = 0``, which
meets the new branch at distance ``eps`` from the bifurcation point ``y*`` and not the
old one (whose tangent is ``<., .>_w``-orthogonal to ``d`` there, up to O(eps)); from it
the pseudo-arclength continuation follows the branch away from ``y*`` with stability,
until the end of the span, a fold it cannot pass, or self-contact of the curve.

Directions (:func:`~qsa.continuation.detection.switching_directions`): at a double
eigenvalue of a circle (O(2)) all directions of the critical plane are rotations of one,
so one branch; of a D_n-symmetric state (an ``n``-pulse) the fixed lines of the
reflections (isotropy directions), one per group orbit; at a simple eigenvalue ``phi``
and ``-phi`` unless a symmetry maps one to the other.

The new branch keeps the symmetry of its first point when the grid holds it (a node
shift by ``N/m``: ``m`` must divide ``N``, so odd orders on Fourier grids): its states
are kept in that fixed-point space, which prevents jumping to other branches near its
own bifurcations, and its spectra split into Bloch sectors.
"""

from __future__ import annotations

import numpy as np

from qsa._checks import real_number
from qsa.constraints import bind_constraints
from qsa.continuation.branch import Bifurcation, Branch
from qsa.continuation.detection import switching_directions
from qsa.continuation.steps import Problem, corrector, parse_span
from qsa.continuation.tracking import _arclength, _Stability
from qsa.geometry import helmholtz
from qsa.spectra.symmetry import detect_symmetry

__all__ = ["switch_branch", "perturbation"]


def perturbation(curve, phi):
    """``(d kappa, d L)`` of the normal perturbation ``phi`` in the constant-``g`` layout.

    ``M(phi, 0) = (G phi, g kappa phi)`` (e:Meq); the length changes by
    ``int g kappa phi ds = <kappa, phi>``.

    Parameters
    ----------
    curve : Curve
    phi : ndarray, shape (N,)

    Returns
    -------
    dkappa : ndarray, shape (N,)
    dL : float

    Examples
    --------
    Inflating a circle of radius 1 by ``phi = 1`` lowers its curvature like ``-1/R^2``
    and grows its length by ``2 pi``:

    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> dk, dL = perturbation(Curve.circle(1.0, Fourier(17)), np.ones(17))
    >>> bool(np.allclose(dk, -1.0)), round(dL, 10) == round(2 * np.pi, 10)
    (True, True)
    """
    dk = np.asarray(helmholtz(curve) @ phi).ravel()
    return dk, float(np.sum(curve.dsigma * curve.kappa * phi))


def switch_branch(branch: Branch, bifurcation: Bifurcation, span=None, *, constraints=None,
                  amplitude=None, tol=1e-10, maxiter=10, max_steps=200, ds_max=None,
                  ds_min=None, stability=True, locate=True, ptol=1e-10,
                  stop_at_contact=True) -> list:
    """Follow the branches bifurcating at ``bifurcation``: one :class:`Branch` per direction.

    Parameters
    ----------
    branch : Branch
        The branch the bifurcation was found on (its ``energy_factory`` is used).
    bifurcation : Bifurcation
        One of ``branch.bifurcations`` with ``kind == "branch"``.
    span : (a, b) or (a, b, step), optional
        The parameter range the new branches may cover (they end when ``p`` leaves it)
        and the initial arclength step (default: 1/50 of the range). Default: the
        range of ``branch``.
    constraints : sequence, optional
        Default: the branch's.
    amplitude : float, optional
        Distance ``eps`` of the first point from the bifurcation (weighted norm);
        default the step.
    tol, maxiter, max_steps, ds_max, ds_min, stability, locate, ptol, stop_at_contact
        As in :func:`~qsa.continuation.continuation`.

    Returns
    -------
    list of Branch
        Each with ``origin = bifurcation``; a direction whose first point does not
        converge gives a branch with a failure status and the bifurcation point only.

    Raises
    ------
    ValueError
        ``bifurcation`` is a fold or has no critical modes, or a bad ``span``.

    Examples
    --------
    The mode-2 branch point of the faceting circles: one branch (O(2)), 2-fold symmetric:

    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.95, 0.1, grid=17)
    >>> fam = lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls)
    >>> b = continuation(fam, eq.curve, "L_star", (eq.params["L_star"], 5.45, -0.05))
    >>> new = switch_branch(b, b.bifurcations[0], span=(5.3, 5.7, 0.01), max_steps=3)
    >>> len(new), new[0].origin is b.bifurcations[0], bool(new[0].points[-1].curve.kappa.std() > 0)
    (1, True, True)
    """
    if not isinstance(branch, Branch) or branch.energy_factory is None:
        raise ValueError("branch must be a Branch returned by qsa.continuation.continuation")
    if not isinstance(bifurcation, Bifurcation):
        raise ValueError("bifurcation must be one of branch.bifurcations")
    if bifurcation.kind != "branch" or not bifurcation.modes:
        raise ValueError(f"bifurcation is a {bifurcation.kind} without critical modes: no "
                         "branch to switch to (pick one with kind == 'branch')")
    factory = branch.energy_factory
    cons = (branch.constraints if constraints is None
            else bind_constraints(constraints, bifurcation.curve))
    if span is None:
        span = (float(np.min(branch.values)), float(np.max(branch.values)))
    span = tuple(float(v) for v in span)
    if len(span) not in (2, 3) or not np.all(np.isfinite(span)) or span[0] == span[1]:
        raise ValueError(f"span must be (a, b) or (a, b, step) with a != b, got {span!r}")
    step = abs(span[2]) if len(span) == 3 else abs(span[1] - span[0]) / 50
    vals, _ = parse_span((span[0], span[1]))
    if step == 0:
        raise ValueError("span: the step must be non-zero")
    eps = step if amplitude is None else real_number(amplitude, "amplitude", positive=True)
    sym_old = bifurcation.symmetry if bifurcation.symmetry is not None else branch.symmetry
    eq = bifurcation.equilibrium
    if sym_old is None:
        sym_old = detect_symmetry(eq.curve)
    p_star = float(bifurcation.parameter)
    out = []
    for phi in switching_directions(bifurcation, sym_old):
        out.append(_follow(factory, cons, eq.curve, p_star, phi, eps, vals, step, branch.param,
                           bifurcation, dict(tol=tol, maxiter=maxiter, max_steps=max_steps,
                                             ds_max=ds_max, ds_min=ds_min,
                                             stability=stability, locate=locate, ptol=ptol,
                                             contact=stop_at_contact)))
    return out


def _follow(factory, cons, c_star, p_star, phi, eps, vals, step, param, bif, opts):
    dk, dL = perturbation(c_star, phi)
    L = c_star.length()
    # the new branch's reference: the perturbed curve (its phase condition, unfolding fields)
    scale = np.sqrt(np.sum(c_star.grid.weights * dk * dk) + dL * dL)
    a = eps / max(scale, 1e-300)
    ref = c_star.__class__(c_star.kappa + a * dk, L + a * dL, c_star.grid, c_star.theta0,
                           c_star.origin)
    sym = detect_symmetry(ref, tol=1e-10)
    prob = Problem(factory, ref, p_star, cons or None, symmetry=sym)
    n = prob.system.size
    y_star = np.append(prob.system.pack(c_star), p_star)
    d = np.zeros(n + 1)
    d[: prob.N] = dk
    d[prob.N] = dL
    d /= np.sqrt(np.sum(prob.weight(n) * d * d))
    y1, ok, _ = corrector(prob, y_star + eps * d, d, opts["tol"], opts["maxiter"] + 10)
    stab = _Stability(opts["stability"], sym, cons or None)
    if not ok:
        return Branch(param, (), (), (), "pseudo-arclength", False, -1,
                      f"the first point of the new branch (at distance {eps:.3g} from "
                      f"{param}={p_star:.10g}) did not converge: try another amplitude",
                      0, 1, 0, (), sym, 0, 0, factory, tuple(cons or ()), bif)
    prev = y1 - y_star
    prev /= np.sqrt(np.sum(prob.weight(n) * prev * prev))
    prob = prob.rebased(prob.system.curve(y1[:n]), float(y1[-1]))
    x1 = prob.system.pack(prob.system.curve(y1[:n]))
    o = dict(tol=opts["tol"], maxiter=opts["maxiter"], ptol=opts["ptol"],
             locate=opts["locate"], contact=opts["contact"])
    br = _arclength(factory, prob, x1, vals, step, param, opts["max_steps"], opts["ds_max"],
                    opts["ds_min"], stab, True, o, p0=float(y1[-1]), prev=prev)
    note = f"; switched at {param}={p_star:.10g}"
    m = bif.sector
    if bif.symmetry is not None and bif.symmetry.circle and m > 1 and c_star.N % m:
        note += (f"; N = {c_star.N} is not a multiple of {m}: the branch is followed without "
                 f"its {m}-fold symmetry")
    return Branch(br.param, br.points, br.folds, br.branch_points, br.method, br.success,
                  br.status, br.message + note, br.n_steps,
                  br.n_rejected, br.n_newton, br.bifurcations, br.symmetry, br.n_eigensolves,
                  br.n_locate_solves, factory, tuple(cons or ()), bif)
