"""mpmath references for the periodic orbits of the front equation (60 digits by default).

Provenance: the orbits of ``alpha^2 psi'' - W'(psi) = nu1`` (e:Facet-CP) have the first
integral ``alpha^2 psi'^2 / 2 = P(psi) = W(psi) + nu1 psi + nu2`` (e:Fint), so the period
is the integral below, evaluated in multiple precision independently of
:mod:`qsa.equilibria.orbit` (double precision, Gauss-Legendre panels in ``v``).
"""

import mpmath

__all__ = ["mp_period"]


def mp_period(alpha, nu1, nu2, a0, b0, kstar=5.0, dps=60):
    """The period ``2 int_a^b alpha / sqrt(2 P(psi)) dpsi`` of the front equation's orbit.

    ``P(psi) = W(psi) + nu1 psi + nu2`` with the quartic well
    ``W = psi^2 (psi - kstar)^2 / 4``; ``a, b`` are the roots of ``P`` found by
    ``mpmath.findroot`` from ``a0, b0`` (the turning points of the orbit). Computed at
    ``dps`` digits by tanh-sinh quadrature after ``psi = m + h sin(u)``, with geometric
    splits toward the ends where the integrand peaks near a separatrix.
    """
    with mpmath.workdps(dps):
        k = mpmath.mpf(kstar)

        def P(x):
            return x**2 * (x - k) ** 2 / 4 + nu1 * x + nu2

        def dP(x):
            return x * (x - k) * (2 * x - k) / 2 + nu1

        a = mpmath.findroot(P, a0, df=dP)
        b = mpmath.findroot(P, b0, df=dP)
        m, h = (a + b) / 2, (b - a) / 2

        def f(u):
            p = P(m + h * mpmath.sin(u))
            return alpha * h * mpmath.cos(u) / mpmath.sqrt(2 * p) if p > 0 else mpmath.mpf(0)

        # geometric splits resolve the near-singular peaks at the separatrix end
        e = [mpmath.mpf(10) ** -j for j in range(dps // 2, 0, -3)]
        hp = mpmath.pi / 2
        nodes = [-hp] + [-hp + x for x in e] + [0] + [hp - x for x in reversed(e)] + [hp]
        return 2 * mpmath.quad(f, nodes)
