"""Constrained linearization: the pressurized ring (Lévy), the vesicle, the flow it linearizes.

The ring ``CanhamHelfrich(eps) + Pressure(p)`` at fixed length is a circle of radius R
for every p, with ``mu_L = -R (p + eps / (2 R^3))``. Along normal modes ``cos k theta``
the Lagrangian ``F = E - p A - mu_L L`` has the second variation (``A'' = int kappa phi^2``,
``L'' = int |grad_s phi|^2``)

    F'' = eps (k^2 - 1)^2 / R^4 + p (k^2 - 1) / R   (per unit <phi, phi>),

so ``P J P`` has ``lambda_k = -(k^2 - 1) (eps (k^2 - 1) / R^4 + p / R)`` for ``k >= 2``
(double), ``0`` for ``k = 1`` (translations) and no ``k = 0`` mode (it changes the
length: excluded). ``lambda_n`` crosses zero at Lévy's pressure ``p_n = -(n^2 - 1) eps / R^3``.
"""

import json
import warnings

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.constraints import FixedArea, FixedLength, constraint_normals, project_velocity
from qsa.energies import CanhamHelfrich, Pressure
from qsa.equilibria import polish
from qsa.linalg import to_dense
from qsa.spectra import kernel_report, linearization, normal_operator, spectrum
from tests.helpers import fitted_order

EPS, R = 0.7, 1.3


def levy_eigenvalues(p, kmax, eps=EPS, R=R):
    k = np.arange(2, kmax + 1)
    return np.repeat(-(k**2 - 1) * (eps * (k**2 - 1) / R**4 + p / R), 2)


def levy_pressure(n, eps=EPS, R=R):
    return -(n**2 - 1) * eps / R**3


def ring(p, grid):
    return CanhamHelfrich(EPS) + Pressure(p), Curve.circle(R, grid)


def non_kernel(s):
    return np.sort(s.eigenvalues[~s.is_kernel])[::-1]


@pytest.mark.parametrize("p", [0.4, 0.0, -2.0, -5.5, -10.0])
def test_ring_spectrum_is_the_closed_form(p):
    E, c = ring(p, Fourier(65))
    s = spectrum(E, c, constraints=[FixedLength()], reject_spurious=False)
    assert s.status == 0 and s.success, s.message
    assert s.relative_residual < 1e-12
    assert s.constraint_multipliers[0] == pytest.approx(-R * (p + EPS / (2 * R**3)), rel=1e-10)
    # N - 1 eigenvalues: the length-changing direction is excluded, not reported
    assert s.eigenvalues.size == c.N - 1 and s.n_kernel == 2
    assert np.abs(s.eigenvalues[s.is_kernel]).max() < 1e-10
    ref = levy_eigenvalues(p, 12)
    got = non_kernel(s)[: ref.size]
    assert np.allclose(got, np.sort(ref)[::-1], rtol=1e-9, atol=0)
    assert s.n_unstable == int(np.sum(ref > 0))
    assert "fixed L" in s.message


@pytest.mark.parametrize("n", [2, 3, 4])
def test_mode_n_crosses_zero_at_levys_pressure(n):
    """A double crossing exactly at p_n: the mode-n pair changes sign, n_unstable by 2."""
    pn = levy_pressure(n)
    c = Curve.circle(R, Fourier(65))
    cos_n = np.cos(2 * np.pi * n * c.grid.s)
    sin_n = np.sin(2 * np.pi * n * c.grid.s)

    def mode_n(p):
        s = spectrum(CanhamHelfrich(EPS) + Pressure(p), c, constraints=[FixedLength()],
                     reject_spurious=False)
        # the eigenvectors that live in span(cos n theta, sin n theta)
        V = s.eigenvectors
        w = c.dsigma
        frac = ((cos_n * w) @ V) ** 2 / (cos_n**2 @ w) + ((sin_n * w) @ V) ** 2 / (sin_n**2 @ w)
        pick = np.flatnonzero(frac > 0.999)
        assert pick.size == 2
        return s.eigenvalues[pick], s.n_unstable

    lo, n_lo = mode_n(pn * (1 - 1e-6))
    hi, n_hi = mode_n(pn * (1 + 1e-6))
    assert np.all(lo < 0) and np.all(hi > 0)
    assert n_hi == n_lo + 2 == 2 * (n - 1)
    # the crossing located by a secant on the computed eigenvalue (linear in p)
    pa, pb = 0.9 * pn, 1.1 * pn
    la, lb = mode_n(pa)[0].mean(), mode_n(pb)[0].mean()
    root = pa - la * (pb - pa) / (lb - la)
    assert root == pytest.approx(pn, rel=1e-9)


def test_shift_invert_agrees_with_the_dense_path():
    E, c = ring(-3.0, Fourier(65))
    dense = spectrum(E, c, constraints=[FixedLength()], reject_spurious=False)
    si = spectrum(E, c, k=8, constraints=[FixedLength()])
    near = dense.eigenvalues[np.argsort(np.abs(dense.eigenvalues))][:8]
    assert np.allclose(np.sort(si.eigenvalues), np.sort(near), rtol=1e-10, atol=1e-10)
    assert si.n_kernel == 2 and si.n_unstable == dense.n_unstable


def test_ring_on_finite_differences_converges_at_order_two():
    Ns = [64, 128, 256]
    errs = []
    ref = levy_eigenvalues(-1.5, 4)
    for N in Ns:
        E, c = ring(-1.5, FiniteDifference(N))
        s = spectrum(E, c, constraints=[FixedLength()])
        assert s.success and s.n_kernel == 2, s.message
        errs.append(np.abs(non_kernel(s)[: ref.size] / ref - 1).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


@pytest.mark.parametrize("gauge", ["comoving", "scaled"])
def test_other_gauges_share_the_constrained_spectrum(gauge):
    E, c = ring(0.4, Fourier(49))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = spectrum(E, c, gauge=gauge, constraints=[FixedLength()])
    ev = np.sort(np.real(s.eigenvalues[~s.is_kernel]))[::-1][:8]
    assert np.allclose(ev, levy_eigenvalues(0.4, 5), rtol=1e-8)


def test_linearization_matrices_of_the_constrained_flow():
    E, c = ring(0.4, Fourier(33))
    cons = [FixedLength()]
    J = to_dense(linearization(E, c, gauge="normal", constraints=cons))
    # P J P: self-adjoint in <.,.>, kills the excluded direction kappa
    WJ = c.dsigma[:, None] * J
    assert np.abs(WJ - WJ.T).max() < 1e-10 * np.abs(WJ).max()
    assert np.abs(J @ c.kappa).max() < 1e-10 * np.abs(J).max()
    ev = np.sort(np.linalg.eigvalsh(0.5 * (WJ + WJ.T) / c.dsigma[0]))[::-1]
    assert np.allclose(ev[3:11], levy_eigenvalues(0.4, 5), rtol=1e-8)  # after 3 zeros


def ellipse(grid, a=1.25, b=0.8):
    return Curve.polar(lambda t: a * b / np.sqrt((b * np.cos(t)) ** 2 + (a * np.sin(t)) ** 2),
                       grid)


VESICLE = [FixedLength(2 * np.pi), FixedArea(0.9 * np.pi)]  # reduced area 0.9


@pytest.fixture(scope="module")
def vesicle():
    r = polish(CanhamHelfrich(1.0), ellipse(Fourier(65)), constraints=VESICLE)
    assert r.success and r.residual < 1e-10 * r.residual_scale, r.message
    return r


def test_vesicle_is_stable_with_a_three_dimensional_kernel(vesicle):
    c = vesicle.curve
    s = spectrum(vesicle.energy, c, constraints=VESICLE)
    assert s.status == 0, s.message
    assert s.n_kernel == 3 and s.n_unstable == 0
    assert s.eigenvalues.size <= c.N - 2  # two constrained directions excluded
    assert non_kernel(s)[0] < -30 and s.kernel_tol < 1e-9
    kr = kernel_report(vesicle.energy, c, constraints=VESICLE)
    assert kr.kernel_dimension == 3 == kr.expected_kernel_dimension
    assert kr.lagrange_kernel < 1e-10 and kr.reparameterization < 1e-10
    assert np.abs(kr.rigid_normal).max() < 1e-8
    assert np.allclose(kr.constraint_multipliers, vesicle.constraint_multipliers, rtol=1e-8)
    summary = json.loads(json.dumps(s.summary()))
    assert [k["constraint"] for k in summary["constraints"]] == ["FixedLength", "FixedArea"]


def _reparameterized(c, amp=0.06):
    grid = c.grid
    st = grid.s + amp * np.sin(2 * np.pi * grid.s)
    g = c.length() * (1 + amp * 2 * np.pi * np.cos(2 * np.pi * grid.s))
    return Curve(grid.interpolate(c.kappa, st), g, grid, c.theta0, c.origin)


def euclidean_projection(c, V):
    """V minus its Euclidean (unweighted) projection on the constraint normals."""
    n = constraint_normals(VESICLE, c)
    return V - n.T @ np.linalg.solve(n @ n.T, n @ V)


@pytest.mark.parametrize("uniform", [True, False])
def test_the_constrained_flow_linearizes_to_PJP(vesicle, uniform):
    """Central differences of V_c(U) = P V^n(U) along U + t M(phi, 0), phi in T, equal P J P phi.

    P is the <.,.>-orthogonal projection (weights dsigma): the projection that keeps
    d/dt A = <1, V> and d/dt L = <kappa, V> zero. With non-constant g the Euclidean
    projection differs, does not conserve A or L, and does not linearize to P J P.
    """
    E = vesicle.energy
    c = vesicle.curve if uniform else _reparameterized(vesicle.curve)
    V_c = lambda u: project_velocity(VESICLE, u, E.normal_velocity(u))
    V_e = lambda u: euclidean_projection(u, E.normal_velocity(u))
    s = c.grid.s
    phi = project_velocity(VESICLE, c, np.cos(4 * np.pi * s) + 0.3 * np.sin(6 * np.pi * s))
    U1 = geometry.M(c) @ np.concatenate([phi, np.zeros(c.N)])
    d = 1e-5
    central = lambda f: (f(c.with_U(c.U + d * U1)) - f(c.with_U(c.U - d * U1))) / (2 * d)
    fd, fdE = central(V_c), central(V_e)
    PJP = to_dense(normal_operator(E, c, constraints=VESICLE))
    J = to_dense(normal_operator(E, c))
    scale = np.abs(fd).max()
    assert np.abs(fd - PJP @ phi).max() < 1e-7 * scale
    assert np.abs(fd - J @ phi).max() > 0.1 * scale  # the unconstrained J is not it
    V = np.cos(2 * np.pi * s) + 1.0
    rates = []
    for proj in (project_velocity(VESICLE, c, V), euclidean_projection(c, V)):
        W1 = geometry.M(c) @ np.concatenate([proj, np.zeros(c.N)])
        rates.append([(k.value(c.with_U(c.U + d * W1)) - k.value(c.with_U(c.U - d * W1)))
                      / (2 * d) for k in VESICLE])
    assert np.abs(rates[0]).max() < 1e-8  # the <.,.> projection conserves L and A
    if uniform:  # constant g: both projections coincide
        assert np.abs(fdE - PJP @ phi).max() < 1e-7 * scale
    else:
        assert np.abs(fdE - PJP @ phi).max() > 1e-3 * scale
        assert np.abs(rates[1]).max() > 0.1


def test_circle_with_both_constraints_excludes_one_direction():
    """On a circle n_L = kappa is parallel to n_A = 1: one excluded direction, not two."""
    c = Curve.circle(1.0, Fourier(33))
    s = spectrum(CanhamHelfrich(1.0), c, constraints=[FixedLength(), FixedArea()],
                 reject_spurious=False)
    assert s.success and s.eigenvalues.size == c.N - 1 and s.n_kernel == 2


def test_pressure_balanced_circle_without_constraints():
    """CanhamHelfrich + Pressure(p), p = -eps/(2 R^3): lambda_k = -eps (k^2-1)(k^2-3/2)/R^4.

    With mu_L = 0 the pressure term alone balances bending; the second variation
    eps (k^2-1)^2/R^4 - eps k^2/(2 R^4) + eps/(2 R^4) per unit <phi, phi> (bending, its
    tension part eps/(2R^2) L'' and -p A''), mode 0 included (no length constraint).
    """
    p = -EPS / (2 * R**3)
    s = spectrum(CanhamHelfrich(EPS) + Pressure(p), Curve.circle(R, Fourier(65)),
                 reject_spurious=False)
    assert s.status == 0 and s.n_kernel == 2 and s.eigenvalues.size == 65
    k = np.array([0, 2, 2, 3, 3, 4, 4, 5, 5])
    ref = np.sort(-EPS * (k**2 - 1) * (k**2 - 1.5) / R**4)[::-1]
    assert np.allclose(non_kernel(s)[: ref.size], ref, rtol=1e-9)
