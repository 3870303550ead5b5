"""Non-quartic double wells for the equilibrium tests (equal-depth wells at 0 and kstar)."""

import numpy as np


class SineWell:
    """``W = A sin^2(pi k / kstar)``; its front is ``(2 kstar / pi) arctan(exp(lam sigma))``,
    ``lam = pi sqrt(2 A) / (alpha kstar)``."""

    def __init__(self, kstar=5.0, A=2.0):
        self.kstar, self.A = kstar, A

    def W(self, k):
        return self.A * np.sin(np.pi * k / self.kstar) ** 2

    def dW(self, k):
        return self.A * np.pi / self.kstar * np.sin(2 * np.pi * k / self.kstar)

    def d2W(self, k):
        return 2 * self.A * (np.pi / self.kstar) ** 2 * np.cos(2 * np.pi * k / self.kstar)

    def exact_front(self, sigma, alpha):
        lam = np.pi * np.sqrt(2 * self.A) / (alpha * self.kstar)
        return 2 * self.kstar / np.pi * np.arctan(np.exp(lam * sigma))


class SexticWell:
    """``W = k^2 (k - kstar)^2 (1 + b (k - kstar/2)^2) / 4`` (symmetric, non-quartic)."""

    def __init__(self, kstar=5.0, b=0.3):
        self.kstar, self.b = kstar, b

    def _parts(self, k):
        q = 0.25 * k**2 * (k - self.kstar) ** 2
        dq = 0.5 * k * (k - self.kstar) * (2 * k - self.kstar)
        d2q = 0.5 * (6 * k**2 - 6 * k * self.kstar + self.kstar**2)
        y = k - 0.5 * self.kstar
        return q, dq, d2q, 1 + self.b * y**2, 2 * self.b * y, 2 * self.b

    def W(self, k):
        q, _, _, r, _, _ = self._parts(k)
        return q * r

    def dW(self, k):
        q, dq, _, r, dr, _ = self._parts(k)
        return dq * r + q * dr

    def d2W(self, k):
        q, dq, d2q, r, dr, d2r = self._parts(k)
        return d2q * r + 2 * dq * dr + q * d2r


class SexticPolyWell(SexticWell):
    """The sextic, declaring its coefficients (numpy.polyval order): exact orbit path."""

    @property
    def coefficients(self):
        quartic = np.poly1d([0.25, -0.5 * self.kstar, 0.25 * self.kstar**2, 0, 0])
        factor = np.poly1d([self.b, -self.b * self.kstar, 1 + self.b * self.kstar**2 / 4])
        return (quartic * factor).coeffs


import pytest  # noqa: E402


@pytest.fixture
def sine_well():
    return SineWell()


@pytest.fixture
def sextic_well():
    return SexticWell()


@pytest.fixture
def sextic_poly_well():
    return SexticPolyWell()
