"""The 2N-front profile ``psi_N`` of a heteroclinic splice, its derivatives and residuals.

Section "Formal Equilibrium and Quasi-Steady Analysis" (e:psi_h and the 2N-front
quasi-equilibrium ``psi_N``). With constant arc length ``g = L`` and arc length
``sigma = L s``, corner ``i`` is the arc ``[p_{2i-1}, p_{2i}]`` between an up-front and a
down-front; the curvature is ::

    psi_N(sigma) = sum_i [ psi~(y_i + a_i) - psi~(y_i - a_i) ],

with ``c_i, a_i`` the midpoint and half-length of corner ``i`` and ``y_i = sigma - c_i``
wrapped to ``[-L/2, L/2)`` -- the periodic form of the paper's alternating sum
``sum (-1)^{i+1} psi~(sigma - p_i)``. ``psi~`` is the front cut off at a FIXED arc
length: ``psi~ = chi psi_h + (1 - chi) kstar H(sigma)`` with a C-infinity cutoff
``chi = 1`` for ``|sigma| <= l1`` and ``0`` for ``|sigma| >= l2``; it is monotone and each
corner turns by exactly ``kstar (p_{2i} - p_{2i-1})``.

NOTE: the paper cuts off at ``|s| in [alpha l, 2 alpha l]``, which shrinks with alpha
and leaves an alpha-independent error; with a fixed cutoff the residuals scale like
``exp(-kstar d_min / (sqrt(2) alpha))``, d_min the smallest front spacing (Conventions and errata,
section 5), as long as ``l1 > d_min``.

:class:`SpliceProfile` evaluates ``psi_N``, its arc-length derivatives, its derivatives
in the positions and the residuals ``R_kappa``, ``R_g`` (in double precision, and
``R_kappa`` in mpmath arithmetic for the quartic well); :mod:`qsa.equilibria.splice`
closes the positions and builds the :class:`~qsa.equilibria.result.Equilibrium`.
Residuals (paper's ``R_kappa``, ``R_g``; ``L* = L`` balances the perimeter term): ::

    R_kappa = -alpha^2 psi_N'' + W'(psi_N),   R_g = -alpha^2/2 psi_N'^2 + W(psi_N).
"""

from __future__ import annotations

import mpmath
import numpy as np
from scipy.special import expit

from qsa.energies.wells import is_quartic

__all__ = ["SpliceProfile"]


def _smoothstep(t):
    """C-infinity step S(t) = 0 (t <= 0) ... 1 (t >= 1) and its first two derivatives."""
    t = np.asarray(t, dtype=float)
    inside = (t > 0) & (t < 1)
    tt = np.where(inside, t, 0.5)
    q = 1 / (1 - tt) - 1 / tt
    S = expit(q)
    dq = 1 / (1 - tt) ** 2 + 1 / tt**2
    d2q = 2 / (1 - tt) ** 3 - 2 / tt**3
    S1 = S * (1 - S) * dq
    S2 = S * (1 - S) * (1 - 2 * S) * dq**2 + S * (1 - S) * d2q
    S = np.where(inside, S, (t >= 1).astype(float))
    return S, np.where(inside, S1, 0.0), np.where(inside, S2, 0.0)


class SpliceProfile:
    """``psi_N`` and its arc-length derivatives for given front positions.

    Parameters
    ----------
    front : Heteroclinic
    positions : ndarray, shape (2N,)
        Arc-length positions ``p_1 < p_2 < ... < p_2N`` (up, down, up, down, ...).
    length : float
        Total length L.
    cutoff : (float, float)
        ``(l1, l2)``, fixed arc lengths of the cutoff, ``0 < l1 < l2``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import heteroclinic
    >>> from qsa.equilibria.splice import default_cutoff, polygon_positions
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> prof = SpliceProfile(heteroclinic(0.2, kstar=5.0), p, L, default_cutoff(p, L))
    >>> R_kappa, R_g = prof.residuals(np.linspace(0, L, 7))
    >>> R_kappa.shape, bool(abs(R_kappa[0]) < 1e-4)  # small mid-facet, O(1e-1) at corners
    ((7,), True)
    """

    def __init__(self, front, positions, length, cutoff):
        self.front = front
        self.p = np.asarray(positions, dtype=float)
        self.L = float(length)
        self.l1, self.l2 = (float(v) for v in cutoff)
        self.c = 0.5 * (self.p[0::2] + self.p[1::2])
        self.a = 0.5 * (self.p[1::2] - self.p[0::2])

    def cut_front(self, x):
        """``psi~, psi~', psi~''`` at local coordinates x (any shape).

        ``psi~ - kstar H(x) = chi (psi_h - kstar H(x))``: the front's tail ``gap`` is
        computed without cancellation and the cutoff ``chi`` is evaluated only where it
        acts (``l1 < |x| < l2``). For the quartic well the front is logistic, so one
        exponential gives all three (``q = e^{-lambda |x|} / (1 + e^{-lambda |x|})``:
        ``gap = -+ kstar q``, ``psi_h' = lambda kstar q (1 - q)``, ``psi_h'' = -+
        lambda^2 kstar q (1 - q) (1 - 2 q)``); other wells use the front's quadrature
        and ``psi_h'' = W'(psi_h) / alpha^2``.

        Parameters
        ----------
        x : array_like
            Local coordinate (distance from the front).

        Returns
        -------
        psi, dpsi, d2psi : ndarray, shape like ``x``

        Examples
        --------
        >>> import numpy as np
        >>> from qsa.equilibria import heteroclinic
        >>> front = heteroclinic(0.1, kstar=5.0)
        >>> prof = SpliceProfile(front, [0.0, 1.0, 2.0, 3.0], 8.0, (1.0, 2.0))
        >>> x = np.array([-0.3, 0.0, 0.2, 1.5, 2.5])  # tail, centre, tail, cutoff, step
        >>> v0, v1, v2 = prof.cut_front(x)
        >>> bool(np.allclose(v0[:3], front(x[:3]), rtol=1e-14))
        True
        >>> bool(v0[-1] == 5.0 and v1[-1] == 0.0 and v2[-1] == 0.0)  # beyond l2: the step
        True
        """
        x = np.asarray(x, dtype=float)
        f = self.front
        k = f.kstar
        r = np.abs(x)
        pos = x > 0
        live = r < self.l2  # beyond l2 the cut front is the bare step
        if f.closed_form:
            lam = f.rates[0]
            sg = np.where(pos, -k, k) * live
            q = np.exp(-lam * r)
            q /= 1 + q
            q1 = q * (1 - q)
            gap = sg * q
            v1 = (lam * k) * q1 * live
            v2 = (lam * lam) * sg * q1 * (1 - 2 * q)
        else:
            xs = np.where(live, x, 0.0)
            psi = f(xs)
            gap = np.where(pos, -f.complement(xs), psi) * live  # psi_h - kstar H(x)
            v1 = f.derivative(xs) * live
            v2 = (f.well.dW(psi) / f.alpha**2) * live
        v0 = gap + k * pos
        mid = np.flatnonzero(live & (r > self.l1))
        if mid.size:
            w = self.l2 - self.l1
            f0, f1, f2 = v0.reshape(-1), v1.reshape(-1), v2.reshape(-1)  # views
            S, S1, S2 = _smoothstep((self.l2 - r.reshape(-1)[mid]) / w)
            dchi, d2chi = -np.sign(x.reshape(-1)[mid]) * S1 / w, S2 / w**2
            g, d1 = gap.reshape(-1)[mid], f1[mid]
            f0[mid] = f0[mid] + (S - 1) * g
            f1[mid] = dchi * g + S * d1
            f2[mid] = d2chi * g + 2 * dchi * d1 + S * f2[mid]
        return v0, v1, v2

    def local(self, sigma):
        """Wrapped coordinates ``y_i = sigma - c_i`` in [-L/2, L/2), shape (..., N).

        Parameters
        ----------
        sigma : array_like
            Arc lengths.

        Returns
        -------
        ndarray, shape ``sigma.shape + (N,)``
        """
        y = np.asarray(sigma, dtype=float)[..., None] - self.c
        return (y + 0.5 * self.L) % self.L - 0.5 * self.L

    def __call__(self, sigma, derivatives=False):
        """``psi_N(sigma)`` (and ``psi_N', psi_N''`` when ``derivatives``)."""
        y = self.local(sigma)
        up = self.cut_front(y + self.a)
        dn = self.cut_front(y - self.a)
        out = [np.sum(u - d, axis=-1) for u, d in zip(up, dn, strict=True)]
        return tuple(out) if derivatives else out[0]

    def position_derivatives(self, sigma):
        """``d psi_N / d p_j`` at sigma, shape (..., 2N).

        Parameters
        ----------
        sigma : array_like

        Returns
        -------
        ndarray, shape ``sigma.shape + (2N,)``
        """
        y = self.local(sigma)
        up = self.cut_front(y + self.a)[1]
        dn = self.cut_front(y - self.a)[1]
        out = np.empty(y.shape[:-1] + (2 * len(self.a),))
        out[..., 0::2] = -up
        out[..., 1::2] = dn
        return out

    def residuals(self, sigma):
        """``(R_kappa, R_g)`` at sigma (the perimeter term balanced, ``L* = L``).

        Parameters
        ----------
        sigma : array_like

        Returns
        -------
        R_kappa, R_g : ndarray, shape like ``sigma``
        """
        psi, d1, d2 = self(sigma, derivatives=True)
        W = self.front.well
        al = self.front.alpha
        return -(al**2) * d2 + W.dW(psi), -0.5 * al**2 * d1**2 + W.W(psi)

    def residual_kappa_mp(self, sigma, dps=50):
        """``R_kappa`` at the points sigma in mpmath arithmetic (quartic well only).

        The cancellation in ``-alpha^2 psi'' + W'(psi)`` limits double precision to
        about 1e-13 of the largest term; at ``dps`` digits exponentially small residuals
        are resolved. Returns a list of ``mpmath.mpf``.
        """
        f = self.front
        if not is_quartic(f.well, f.kstar):
            raise ValueError("residual_kappa_mp needs the quartic well")
        with mpmath.workdps(dps):
            k, al = mpmath.mpf(f.kstar), mpmath.mpf(f.alpha)
            lam = k / (mpmath.sqrt(2) * al)
            l1, l2, L = mpmath.mpf(self.l1), mpmath.mpf(self.l2), mpmath.mpf(self.L)

            def dW(x):
                return x * (x - k) * (2 * x - k) / 2

            def step(t):
                if t <= 0:
                    return mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
                if t >= 1:
                    return mpmath.mpf(1), mpmath.mpf(0), mpmath.mpf(0)
                q = 1 / (1 - t) - 1 / t
                S = 1 / (1 + mpmath.exp(-q))
                dq = 1 / (1 - t) ** 2 + 1 / t**2
                d2q = 2 / (1 - t) ** 3 - 2 / t**3
                return S, S * (1 - S) * dq, S * (1 - S) * (1 - 2 * S) * dq**2 + S * (1 - S) * d2q

            def cut(x):
                if abs(x) >= l2:
                    return (k if x > 0 else mpmath.mpf(0)), mpmath.mpf(0), mpmath.mpf(0)
                e = mpmath.exp(-lam * x)
                psi = k / (1 + e)
                gap = -k * e / (1 + e) if x > 0 else psi
                dpsi = lam * psi * (1 - psi / k)
                d2psi = dW(psi) / al**2
                S, S1, S2 = step((l2 - abs(x)) / (l2 - l1))
                w = l2 - l1
                sg = 1 if x > 0 else -1
                chi, dchi, d2chi = S, -sg * S1 / w, S2 / w**2
                H = k if x > 0 else 0
                return (H + chi * gap, dchi * gap + chi * dpsi,
                        d2chi * gap + 2 * dchi * dpsi + chi * d2psi)

            out = []
            for s in np.atleast_1d(sigma):
                s = mpmath.mpf(float(s))
                v0 = v2 = mpmath.mpf(0)
                for c, a in zip(self.c, self.a, strict=True):
                    y = s - mpmath.mpf(float(c))
                    y = (y + L / 2) % L - L / 2
                    a = mpmath.mpf(float(a))
                    u, d = cut(y + a), cut(y - a)
                    v0 += u[0] - d[0]
                    v2 += u[2] - d[2]
                out.append(-(al**2) * v2 + dW(v0))
            return out
