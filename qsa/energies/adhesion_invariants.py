"""The two-point curve invariants of the adhesion energy (lem:TP_invar, e:Ad-Invar).

Rigid invariance of a two-point energy makes its extrinsic gradient ``(𝔸.n + kappa B, 0)``
orthogonal to the rigid motions (e:Adh-Ex_grad, lem:kerM): the *curvature forms*
``int (𝔸.n + kappa B)(v0.n) dsigma = 0`` and ``int (𝔸.n + kappa B)(gamma.tau) dsigma = 0``.
With ``nabla_s B = 𝔸.tau`` and an integration by parts the rotation becomes e:Ad-Invar,
``int (𝔸.n)(gamma.tau) - (𝔸.tau)(gamma.n) dsigma = 0``, and the translations
``int 𝔸 dsigma = 0`` (the *force forms*). Lemma TP_invar states more: split ``S x S``
into the level sets ``E_r = {|gamma(s) - gamma(s~)| = r}``; for *each* r the integrands of
e:Ad-Rot, ``(n.gamma)(gamma~.tau) - (n.gamma~)(gamma.tau)``, and of e:Ad-Trans,
``(n.d)(n.v0) + (tau.d)(tau.v0)``, integrate to zero over ``E_r`` (against
``g g~ dH dr``).

Discretely, with node weights ``w_i = dsigma_i``, the integral over the pairs whose
distance falls in a level ``(r_k, r_{k+1}]`` is the sum of ``w_i w_j f(i, j)`` over the
ordered pairs in it. Both integrands are odd under ``i <-> j`` (the rotation one equals
``gamma_i x gamma_j``, the translation one ``d_ij . v0``), so each level's sum, and the force
forms computed from the discrete force, vanish to round-off. The curvature forms use
``nabla_s B = 𝔸.tau``, which the node quadrature satisfies only to its accuracy: they
vanish spectrally on Fourier grids and at second order on finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa.curve import Curve
from qsa.energies.adhesion import Adhesion, adhesion_pairs, pair_list

__all__ = ["TwoPointInvariants", "adhesion_invariants", "two_point_terms"]

# pairs per chunk of the level-set sums
_CHUNK = 1 << 20


def two_point_terms(energy) -> tuple:
    """The two-point (``Adhesion``) summands of ``energy``, possibly empty.

    Parameters
    ----------
    energy : Energy

    Returns
    -------
    tuple of Adhesion
    """
    terms = energy.terms() if hasattr(energy, "terms") else (energy,)
    return tuple(t for t in terms if isinstance(t, Adhesion))


@dataclass(frozen=True)
class TwoPointInvariants:
    """Relative residuals of the two-point invariants of one curve.

    Each residual is the invariant's value over the integral of the absolute value of its
    integrand (so 1 means no cancellation at all).

    Attributes
    ----------
    translation_force, rotation_force : float
        ``|int 𝔸 dsigma|`` (worst component) and e:Ad-Invar's first line: round-off.
    translation_curvature, rotation_curvature : float
        ``int (𝔸.n + kappa B)(e_k.n) dsigma`` (worst k) and
        ``int (𝔸.n + kappa B)(gamma.tau) dsigma``: the quadrature's accuracy.
    radii : ndarray, shape (n_levels + 1,)
        Edges of the distance levels, from 0 to the kernel's cutoff (or the diameter).
    rotation_levels : ndarray, shape (n_levels,)
        Per level, e:Ad-Rot's discrete integral over it, relative; NaN for a level that
        holds no node pair.
    translation_levels : ndarray, shape (n_levels, 2)
        The same for e:Ad-Trans with ``v0 = e_1, e_2``.
    level_set_max : float
        The largest of ``rotation_levels`` and ``translation_levels`` (NaN skipped).
    """

    translation_force: float
    rotation_force: float
    translation_curvature: float
    rotation_curvature: float
    radii: np.ndarray
    rotation_levels: np.ndarray
    translation_levels: np.ndarray
    level_set_max: float

    def summary(self) -> dict:
        """JSON-serialisable dict of the scalar residuals.

        Returns
        -------
        dict
        """
        names = ("translation_force", "rotation_force", "translation_curvature",
                 "rotation_curvature", "level_set_max")
        return {k: float(getattr(self, k)) for k in names} | {"n_levels": self.radii.size - 1}


def _relative(value, scale):
    return float(np.abs(value) / scale) if scale > 0 else 0.0


def adhesion_invariants(energy, curve: Curve, n_levels=32) -> TwoPointInvariants:
    """Measure lem:TP_invar (per level set) and e:Ad-Invar for the two-point part of ``energy``.

    Parameters
    ----------
    energy : Energy
        An ``Adhesion`` or a sum holding one or more (their fields add).
    curve : Curve
    n_levels : int
        Number of equal distance levels between 0 and the largest kernel cutoff (the
        curve's diameter if smaller). O(N + pairs) work.

    Returns
    -------
    TwoPointInvariants

    Raises
    ------
    ValueError
        If ``energy`` has no two-point term, or ``n_levels`` is not a positive integer.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Adhesion
    >>> c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t), Fourier(257))
    >>> inv = adhesion_invariants(Adhesion(A0=10.0, l_star=0.3), c, n_levels=8)
    >>> bool(inv.level_set_max < 1e-13), bool(inv.rotation_force < 1e-13)
    (True, True)
    >>> bool(inv.rotation_curvature < 1e-11)  # the quadrature's accuracy
    True
    """
    if isinstance(n_levels, bool) or int(n_levels) != n_levels or n_levels < 1:
        raise ValueError(f"n_levels must be a positive integer, got {n_levels!r}")
    n_levels = int(n_levels)
    terms = two_point_terms(energy)
    if not terms:
        raise ValueError("energy has no two-point (Adhesion) term to measure invariants of")

    x, y = curve.positions()
    tau, n = curve.tangent(), curve.normal()
    w = curve.dsigma
    B = np.zeros(curve.N)
    force = np.zeros((curve.N, 2))
    for t in terms:
        b, f = t.fields(curve)
        B, force = B + b, force + f
    radius = np.hypot(x, y)

    # force forms (e:Ad-Invar, the translations with A')
    An = force[:, 0] * n[0] + force[:, 1] * n[1]
    At = force[:, 0] * tau[0] + force[:, 1] * tau[1]
    gt = x * tau[0] + y * tau[1]
    gn = x * n[0] + y * n[1]
    fnorm = np.hypot(force[:, 0], force[:, 1])
    translation_force = max(_relative(force[:, e] @ w, fnorm @ w) for e in (0, 1))
    rotation_force = _relative(w @ (An * gt - At * gn), w @ (np.abs(An * gt) + np.abs(At * gn)))

    # curvature forms (orthogonality of the extrinsic gradient to the rigid motions)
    ext = An + curve.kappa * B
    translation_curvature = max(_relative(w @ (ext * n[e]), w @ np.abs(ext)) for e in (0, 1))
    rotation_curvature = _relative(w @ (ext * gt), w @ (np.abs(ext) * radius))

    # level sets: ordered pairs (i, j) and (j, i), i < j, by distance
    reach = max(t.kernel.cutoff_distance() for t in terms)
    diameter = np.hypot(np.ptp(x), np.ptp(y))
    rmax = min(reach, diameter)
    if rmax == reach and len(terms) == 1 and terms[0].method == "neighbours":
        i, j = adhesion_pairs(terms[0].kernel, x, y)  # the energy's own (cached) list
    else:
        i, j = pair_list(x, y, rmax)
    radii = np.linspace(0.0, rmax, n_levels + 1)
    nx, ny, tx, ty = n[0], n[1], tau[0], tau[1]
    n_g, t_g = nx * x + ny * y, tx * x + ty * y

    def rot(p, q, d):
        # (n_p . gamma_p)(tau_p . gamma_q) - (n_p . gamma_q)(tau_p . gamma_p)
        return n_g[p] * (tx[p] * x[q] + ty[p] * y[q]) - (nx[p] * x[q] + ny[p] * y[q]) * t_g[p]

    def trans(e):
        def f(p, q, d):  # d = gamma_p - gamma_q
            nd = nx[p] * d[0] + ny[p] * d[1]
            td = tx[p] * d[0] + ty[p] * d[1]
            return nd * n[e][p] + td * tau[e][p]
        return f

    forms = (rot, trans(0), trans(1))
    value = np.zeros((3, n_levels))
    scale = np.zeros((3, n_levels))
    # ordered pairs (i, j) and (j, i), i < j, summed per distance level: in chunks of
    # pairs, so the temporaries stay small however many pairs interact
    for start in range(0, i.size, _CHUNK):
        a, b = i[start:start + _CHUNK], j[start:start + _CHUNK]
        d = (x[a] - x[b], y[a] - y[b])
        level = np.clip(np.searchsorted(radii, np.hypot(*d), side="left") - 1, 0,
                        n_levels - 1)
        ww = w[a] * w[b]
        for k, f in enumerate(forms):
            fa, fb = f(a, b, d), f(b, a, (-d[0], -d[1]))
            value[k] += np.bincount(level, ww * (fa + fb), n_levels)
            scale[k] += np.bincount(level, ww * (np.abs(fa) + np.abs(fb)), n_levels)

    def rel(pair):
        value, scale = pair
        out = np.full(n_levels, np.nan)
        filled = scale > 0
        out[filled] = np.abs(value[filled]) / scale[filled]
        return out

    rotation_levels = rel((value[0], scale[0]))
    translation_levels = np.column_stack([rel((value[k], scale[k])) for k in (1, 2)])
    both = np.concatenate([rotation_levels, translation_levels.ravel()])
    level_set_max = float(np.nanmax(both)) if np.isfinite(both).any() else 0.0
    return TwoPointInvariants(translation_force, rotation_force, translation_curvature,
                              rotation_curvature, radii, rotation_levels, translation_levels,
                              level_set_max)
