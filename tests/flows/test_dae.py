"""DAE flow models: analytic Jacobians, signs, exact circle, energy dissipation, bad input."""

import json
import math
import zlib
from dataclasses import replace

import numpy as np
import pytest
from scipy.sparse.linalg import splu

from qsa.energies import Perimeter
from qsa.flows.base import DAESystem, FlowModel
from qsa.flows.dae import CHA, FacetingFlow
from qsa.paper import CONVERGENCE, CHAScenario
from qsa.resample import resample_closed
from tests.helpers import FLOW_MODELS as MODELS
from tests.helpers import SexticWell, numerical_jacobians, paper_curve, smooth_curve

PAPER_CHA = CONVERGENCE.model_params()  # the appendix's convergence example
TABLE_T1 = CHAScenario.literal()  # l* = 0.01: the short kernel's neighbour list


# ----------------------------------------------------------------- curves
def circle(N, R=1.0):
    th = 2 * np.pi * np.arange(N) / N
    return R * np.cos(th), R * np.sin(th)


# ------------------------------------------------------------- Jacobians
@pytest.mark.parametrize("name", list(MODELS))
def test_jacobian_matches_central_differences(name):
    model = MODELS[name]
    x, y = paper_curve(24)
    sys = model.setup(x, y)
    rng = np.random.default_rng(zlib.crc32(name.encode()))  # str hash() is salted per process
    # a random state far from any equilibrium or symmetry
    yy = sys.y0 + 0.05 * rng.standard_normal(sys.size) * (1 + np.abs(sys.y0))
    yd = rng.standard_normal(sys.size)
    Jy, Jd = numerical_jacobians(sys, yy, yd)
    A0 = sys.jacobian(yy, yd, 0.0).toarray()
    A1 = sys.jacobian(yy, yd, 1.0).toarray()
    c = 2.7
    Ac = sys.jacobian(yy, yd, c).toarray()
    assert np.max(np.abs(A0 - Jy)) <= 1e-6 * np.max(np.abs(Jy))
    assert np.max(np.abs((A1 - A0) - Jd)) <= 1e-6 * np.max(np.abs(Jd))
    assert np.max(np.abs(Ac - (Jy + c * Jd))) <= 1e-6 * np.max(np.abs(Jy + c * Jd))


def test_adhesion_jacobian_near_contact():
    # A pinched curve whose two sides are within a few l*: the non-local block matters.
    N = 100
    th = 2 * np.pi * np.arange(1000) / 1000
    x, y, _ = resample_closed(np.cos(th), 0.12 * np.sin(th) + 0.08 * np.sin(th) ** 3, N,
                              method="chord")
    model = CHA(eps=0.05, beta=2.0, rho=1.1, A0=5.0, l_star=0.06, a=1.0)
    sys = model.setup(x, y)
    rng = np.random.default_rng(11)
    yy = sys.y0.copy()
    yy[: 2 * N] += 1e-3 * rng.standard_normal(2 * N)
    yy[2 * N:] += 0.01 * rng.standard_normal(sys.size - 2 * N) * (1 + np.abs(sys.y0[2 * N:]))
    yd = rng.standard_normal(sys.size)
    Jy, Jd = numerical_jacobians(sys, yy, yd, d=1e-7)
    J = sys.jacobian(yy, yd, 1.5).toarray()
    assert np.max(np.abs(J - (Jy + 1.5 * Jd))) <= 1e-6 * np.max(np.abs(Jy + 1.5 * Jd))
    # the adhesion block couples the two sides of the pinch
    rows = slice(4 * N, 5 * N)
    assert np.count_nonzero(J[rows, : 2 * N]) > 2 * N * 8


@pytest.mark.parametrize("name", ["facet", "second-order"])
def test_jacobian_nonzeros_are_linear_in_N(name):
    model = MODELS[name]
    nnz = []
    for N in (100, 200, 400):
        sys = model.setup(*smooth_curve(N))
        nnz.append(sys.jacobian(sys.y0, np.zeros(sys.size), 1.0).nnz)
    assert nnz[1] / nnz[0] == pytest.approx(2.0, rel=0.02)
    assert nnz[2] / nnz[1] == pytest.approx(2.0, rel=0.02)
    assert nnz[0] < 50 * 100


# ---------------------------------------------------------- contract & y0
@pytest.mark.parametrize("name", ["cha-neighbours", "facet"])
def test_contract_and_consistent_initial_state(name):
    model = MODELS[name]
    x, y = smooth_curve(64)
    sys = model.setup(x, y)
    assert isinstance(model, FlowModel) and isinstance(sys, DAESystem)
    n_fields = 5 if isinstance(model, CHA) else 6
    assert sys.size == n_fields * 64 + 1 and sys.y0.shape == (sys.size,)
    assert np.array_equal(sys.error_index, np.arange(128))
    F = sys.residual(sys.y0, np.zeros(sys.size))
    alg = np.setdiff1d(np.arange(sys.size), sys.differential_rows)
    assert np.max(np.abs(F[alg])) <= 1e-10 * (1 + np.max(np.abs(sys.y0)))
    X, Y = sys.positions(sys.y0)
    assert np.max(np.abs(X - x)) < 1e-12 and np.max(np.abs(Y - y)) < 1e-12
    chords = np.hypot(np.roll(X, -1) - X, np.roll(Y, -1) - Y)
    assert sys.length(sys.y0) == pytest.approx(np.sum(chords), rel=1e-13)
    assert np.all(np.isfinite(sys.normal_velocity(sys.y0)))
    meta = sys.metadata()
    assert json.loads(json.dumps(meta)) == meta and meta["N"] == 64
    assert np.isfinite(sys.energy(sys.y0))


def test_setup_projects_nearly_equal_chords():
    x0, y0 = smooth_curve(80)
    rng = np.random.default_rng(5)
    x = x0 + 1e-5 * rng.standard_normal(80)
    y = y0 + 1e-5 * rng.standard_normal(80)
    sys = MODELS["ch-no-adhesion"].setup(x, y)
    X, Y = sys.positions(sys.y0)
    chords = np.hypot(np.roll(X, -1) - X, np.roll(Y, -1) - Y)
    assert np.ptp(chords) <= 1e-12 * np.mean(chords)
    assert 0 < np.max(np.hypot(X - x, Y - y)) < 1e-4


def test_setup_refuses_unequal_chords():
    th = 2 * np.pi * np.arange(80) / 80
    x, y = 2 * np.cos(th + 0.3 * np.sin(th)), np.sin(th + 0.3 * np.sin(th))
    with pytest.raises(ValueError, match="resample"):
        MODELS["facet"].setup(x, y)


# ---------------------------------------------------------------- circle
def test_ccw_circle_has_positive_curvature_second_order():
    errs = []
    Ns = [32, 64, 128, 256]
    for N in Ns:
        sys = MODELS["ch-no-adhesion"].setup(*circle(N, R=2.0))
        kappa = sys.curvature(sys.y0)
        assert np.ptp(kappa) < 1e-12
        errs.append(abs(kappa[0] - 0.5))
    assert np.all(np.array(errs) < 0.01)
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.2)


def test_circle_normal_velocity_closed_form():
    # CH + length penalty on a circle: V = eps kappa^3/2 - beta (L - rho L0) kappa.
    model = CHA(eps=0.1, beta=1.0, rho=1.5)
    R = 1.5
    sys = model.setup(*circle(128, R))
    kappa = sys.curvature(sys.y0)
    L = sys.length(sys.y0)
    V_discrete = 0.1 * kappa**3 / 2 - 1.0 * (L - 1.5 * sys.L0) * kappa
    assert np.max(np.abs(sys.normal_velocity(sys.y0) - V_discrete)) < 1e-11
    V_exact = 0.1 / (2 * R**3) - 1.0 * (2 * np.pi * R) * (1 - 1.5) / R
    assert np.max(np.abs(sys.normal_velocity(sys.y0) - V_exact)) < 1e-3 * abs(V_exact)
    # the circle grows (V > 0): moving outward lowers beta/2 (L - 1.5 L0)^2
    assert V_exact > 0
    # ... and the residual with ydot = V n exactly balances the normal-motion rows
    X, Y = sys.positions(sys.y0)
    ydot = np.zeros(sys.size)
    Vn = sys.normal_velocity(sys.y0)
    tx = (np.roll(X, -1) - np.roll(X, 1)) * 128 / 2
    ty = (np.roll(Y, -1) - np.roll(Y, 1)) * 128 / 2
    tn = np.hypot(tx, ty)
    ydot[:128] = Vn * ty / tn * L / tn
    ydot[128:256] = -Vn * tx / tn * L / tn
    F = sys.residual(sys.y0, ydot)
    assert np.max(np.abs(F[:128])) < 1e-12 and abs(F[-1]) < 1e-12


# ------------------------------------------------------ energy dissipation
def _instantaneous_dEdt(sys, y):
    yd = sys.time_derivative(y)
    assert np.max(np.abs(sys.residual(y, yd))) < 1e-8 * (1 + np.max(np.abs(y)))
    d = 1e-5 / np.max(np.abs(yd[: 3 * sys.N]))
    return (sys.energy(y + d * yd) - sys.energy(y - d * yd)) / (2 * d)


@pytest.mark.parametrize("name", ["ch-no-adhesion", "facet", "facet-user-well"])
def test_energy_dissipation_equals_integral_of_V_squared(name):
    sys = MODELS[name].setup(*smooth_curve(200))
    dEdt = _instantaneous_dEdt(sys, sys.y0)
    assert dEdt < 0
    assert dEdt / -sys.dissipation(sys.y0) == pytest.approx(1.0, abs=1e-3)


def test_cha_energy_dissipation_converges_second_order():
    # With the paper's (long-range) kernel the ratio dE/dt / -int V^2 -> 1 at O(h^2).
    # NOTE: the appendix's eps (kss - kappa^3) would give an O(1) mismatch here.
    model = MODELS["cha-neighbours"]
    Ns = [50, 100, 200]
    errs = []
    for N in Ns:
        sys = model.setup(*smooth_curve(N))
        errs.append(abs(_instantaneous_dEdt(sys, sys.y0) / -sys.dissipation(sys.y0) - 1))
    assert errs[-1] < 2e-3
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.3)


def test_wrong_sign_would_be_caught():
    # Sanity of the dissipation test itself: flipping V's sign makes dE/dt positive.
    sys = MODELS["ch-no-adhesion"].setup(*smooth_curve(100))
    yd = sys.time_derivative(sys.y0)
    d = 1e-5 / np.max(np.abs(yd[:300]))
    dE_back = (sys.energy(sys.y0 - d * yd) - sys.energy(sys.y0 - 2 * d * yd)) / d
    assert dE_back < 0  # the energy falls along the flow on both sides of y0


# ----------------------------------------------------------- backward Euler
def backward_euler(sys, y, k, tol=1e-10, maxiter=20):
    """One implicit Euler step by Newton with sparse LU; returns (y_new, iterations).

    The LU is refreshed on iterations 1, 4, 7, ... (a mildly simplified Newton).
    """
    yn = y
    y = y.copy()
    for it in range(1, maxiter + 1):
        ydot = (y - yn) / k
        if it % 3 == 1:
            lu = splu(sys.jacobian(y, ydot, 1.0 / k))
        dy = lu.solve(sys.residual(y, ydot))
        y = y - dy
        if np.max(np.abs(dy[sys.error_index])) < tol:
            return y, it
    raise AssertionError("Newton did not converge")


@pytest.mark.parametrize(
    "name, N, k, steps",
    [("cha-neighbours", 64, 2e-3, 6), ("ch-no-adhesion", 64, 2e-3, 6), ("facet", 64, 1e-5, 6)],
)
def test_backward_euler_smoke(name, N, k, steps):
    sys = MODELS[name].setup(*paper_curve(N) if name != "facet" else smooth_curve(N))
    y = sys.y0
    E = [sys.energy(y)]
    for _ in range(steps):
        y, it = backward_euler(sys, y, k)
        assert it <= 8
        E.append(sys.energy(y))
        X, Y = sys.positions(y)
        chords = np.hypot(np.roll(X, -1) - X, np.roll(Y, -1) - Y)
        assert np.max(np.abs(chords - sys.length(y) / N)) < 1e-9
    assert np.all(np.diff(E) < 0)


def test_circle_stays_circle_under_backward_euler():
    model = CHA(eps=0.1, beta=1.0, rho=1.5)
    sys = model.setup(*circle(64, 1.0))
    y = sys.y0
    for _ in range(5):
        y, _ = backward_euler(sys, y, 1e-2)
    X, Y = sys.positions(y)
    r = np.hypot(X, Y)
    assert np.ptp(r) < 1e-10 * r.mean()
    assert r.mean() > 1.0  # the circle grows towards rho L0 (V > 0)


# ------------------------------------------------------------- bad input
def test_bad_input_raises_value_error():
    x, y = smooth_curve(64)
    cha = MODELS["cha-neighbours"]
    bad_x = x.copy()
    bad_x[3] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        cha.setup(bad_x, y)
    with pytest.raises(ValueError, match="N=5"):
        cha.setup(x[:5], y[:5])
    with pytest.raises(ValueError, match="counter-clockwise"):
        cha.setup(x[::-1], y[::-1])
    with pytest.raises(ValueError, match="l_star"):
        CHA(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.1, a=1.0).check_resolution(x, y)
    with pytest.raises(ValueError, match="l_star"):
        CHA(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.1, a=1.0).setup(x, y)
    with pytest.raises(ValueError, match="x and y"):
        cha.setup(x, y[:-1])
    with pytest.raises(ValueError, match="eps"):
        CHA(eps=-1.0, beta=1.0, rho=1.5)
    with pytest.raises(ValueError, match="rho"):
        CHA(eps=1.0, beta=1.0, rho=float("nan"))
    with pytest.raises(ValueError, match="adhesion_method"):
        CHA(eps=1.0, beta=1.0, rho=1.0, adhesion_method="fast")
    with pytest.raises(ValueError, match="alpha"):
        FacetingFlow(alpha=0.0, kstar=5.0, beta=5.0, L_star=6.0)
    with pytest.raises(ValueError, match="W"):
        FacetingFlow(alpha=0.1, kstar=5.0, beta=5.0, L_star=6.0, well=object())
    with pytest.raises(ValueError, match="NaN"):
        MODELS["facet"].check_resolution(bad_x, y)


def test_resolution_check_uses_node_spacing():
    x, y = circle(100, 1.0)  # spacing ~ 2 pi / 100 = 0.063
    CHA(eps=0.1, beta=1.0, rho=1.5, A0=1.0, l_star=0.07, a=1.0).check_resolution(x, y)
    with pytest.raises(ValueError, match=r"N >= 11\d"):
        CHA(eps=0.1, beta=1.0, rho=1.5, A0=1.0, l_star=0.055, a=1.0).check_resolution(x, y)
    assert math.isfinite(CHA(eps=0.1, beta=1.0, rho=1.5).setup(x, y).energy(
        CHA(eps=0.1, beta=1.0, rho=1.5).setup(x, y).y0))


def test_neighbour_list_model_matches_dense_model_table_T1_kernel():
    # Table T1 kernel (l* = 0.01) on a 13-fold crenellated start: residual and Newton
    # matrix from the cutoff neighbour list agree with the all-pairs path to 1e-12.
    N = 900
    th = 2 * np.pi * np.arange(4000) / 4000
    r = 0.7 * (1 + 0.12 * np.tanh(4 * np.cos(13 * th)))
    # equal arc length, then setup's projection to equal chords (chord spread ~1e-4 here)
    x, y, _ = resample_closed(r * np.cos(th), r * np.sin(th), N)
    nb = TABLE_T1.model().setup(x, y)
    de = replace(TABLE_T1.model(), adhesion_method="dense").setup(x, y)
    rng = np.random.default_rng(2)
    yy = nb.y0.copy()
    yy[: 2 * N] += 1e-4 * rng.standard_normal(2 * N)
    yd = rng.standard_normal(nb.size)
    Fn, Fd = nb.residual(yy, yd), de.residual(yy, yd)
    assert np.max(np.abs(Fn - Fd)) <= 1e-12 * np.max(np.abs(Fd))
    Jn, Jd = nb.jacobian(yy, yd, 10.0), de.jacobian(yy, yd, 10.0)
    assert Jn.nnz < Jd.nnz / 20  # the list really is short
    assert abs(Jn - Jd).max() <= 1e-12 * abs(Jd).max()
    assert nb.energy(yy) == pytest.approx(de.energy(yy), rel=1e-12)


@pytest.mark.parametrize("name", ["cha-neighbours", "facet", "second-order"])
def test_jacobian_is_canonical_csc(name):
    sys = MODELS[name].setup(*smooth_curve(40))
    for _ in range(2):  # the second call reuses the cached pattern
        J = sys.jacobian(sys.y0, np.ones(sys.size), 3.0)
        assert J.format == "csc" and J.has_canonical_format
        J.check_format(full_check=True)


def test_paper_convergence_example_step_count_with_step_doubling():
    # The appendix example (N = 100, tol 1e-3, physical t = 0.2, Conventions and errata,
    # section 7) with the paper's step doubling: the paper reports 65 steps. A model
    # regression (sign, scaling) changes this count or breaks monotone energy decay.
    sys = CHA(**PAPER_CHA).setup(*paper_curve(100))
    y, t, k, tol, accepted = sys.y0, 0.0, 1e-5, 1e-3, 0
    energies = [sys.energy(y)]
    while t < 0.2 - 1e-12:
        k = min(k, (0.2 - t) / 2)
        y1, _ = backward_euler(sys, y, k)
        y2, _ = backward_euler(sys, y1, k)
        yb, _ = backward_euler(sys, y, 2 * k)
        err = np.max(np.abs(y2[:200] - yb[:200]))
        if err <= tol:
            y, t, accepted = y2, t + 2 * k, accepted + 1
            energies.append(sys.energy(y))
        k *= min(1.3, 0.8 * np.sqrt(tol / err))
    assert 55 <= accepted <= 75
    assert np.all(np.diff(energies) < 0)
    assert energies[-1] < 0.75 * energies[0]


# ------------------------------------------- against the Curve-level energies
@pytest.mark.parametrize("which", ["facet", "ch"])
def test_normal_velocity_agrees_with_curve_energies(which):
    # Independent implementation: the energies' V^n = -G d_kappa E - kappa (g d_g E) on a
    # spectral (Fourier) curve through the same shape. The DAE's V converges to it at
    # second order (equal-chord nodes vs equal arc length nodes also differ at O(h^2)).
    from qsa import Curve, Fourier
    from qsa.energies import CanhamHelfrich, Faceting

    def rfun(t):
        return 1.3 * (1 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t))

    Ns, errs = [128, 256, 512], []
    for N in Ns:
        th = 2 * np.pi * np.arange(4000) / 4000
        x, y, _ = resample_closed(rfun(th) * np.cos(th), rfun(th) * np.sin(th), N)
        if which == "facet":
            model = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0)
            sys = model.setup(x, y)
            energy = Faceting(alpha=0.3, kstar=2.0) + Perimeter(beta=5.0, L_star=6.0)
        else:
            model = CHA(eps=0.1, beta=1.0, rho=1.5)
            sys = model.setup(x, y)
            energy = CanhamHelfrich(eps=0.1) + Perimeter(beta=1.0, L_star=1.5 * sys.L0)
        ref = energy.normal_velocity(Curve.polar(rfun, Fourier(N + 1)))
        # the Fourier curve starts at theta = 0 as the DAE's nodes do; compare on the
        # common parameter through the reference's trigonometric interpolant
        ref_at_nodes = Fourier(N + 1).interpolate(ref, np.arange(N) / N)
        V = sys.normal_velocity(sys.y0)
        errs.append(np.max(np.abs(V - ref_at_nodes)) / np.max(np.abs(ref)))
    slope = -np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert errs[-1] < 0.01
    assert slope == pytest.approx(2.0, abs=0.3)


def test_default_well_is_the_double_well_and_user_wells_are_used():
    from qsa.energies import DoubleWell, Well

    x, y = smooth_curve(48)
    base = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0)
    explicit = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0, well=DoubleWell(2.0))
    s1, s2 = base.setup(x, y), explicit.setup(x, y)
    assert np.array_equal(s1.y0, s2.y0)
    assert s1.metadata()["well"] == "DoubleWell(kstar=2.0)"
    w = SexticWell()
    s3 = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0,
                      well=Well(W=w.W, dW=w.dW, d2W=w.d2W)).setup(x, y)
    assert not np.allclose(s3.normal_velocity(s3.y0), s1.normal_velocity(s1.y0))


# ------------------------------------------------------ resume & simplicity
def test_bound_constants_rebuild_the_same_system_from_a_later_state():
    model = CHA(**PAPER_CHA)
    sys = model.setup(*paper_curve(64))
    y, _ = backward_euler(sys, sys.y0, 1e-3)
    again = model.setup(*sys.positions(y), **sys.bound_constants())
    assert again.L0 == sys.L0 and sys.bound_constants() == {"L0": sys.L0}
    yd = np.random.default_rng(0).standard_normal(sys.size)
    assert np.array_equal(again.residual(y, yd), sys.residual(y, yd))
    assert again.energy(y) == sys.energy(y)
    fac = MODELS["facet"]
    fsys = fac.setup(*smooth_curve(48))
    assert fsys.bound_constants() == {}
    with pytest.raises(ValueError, match="L0"):
        model.setup(*paper_curve(64), L0=-1.0)


def test_self_intersecting_initial_data_is_rejected():
    from qsa.flows.dae import self_intersections

    th = 2 * np.pi * np.arange(400) / 400
    # a limacon with an inner loop: positive signed area but not simple
    r = 0.5 + np.cos(th)
    x, y = r * np.cos(th), r * np.sin(th)
    assert self_intersections(x, y).shape[0] >= 1
    with pytest.raises(ValueError, match="intersects itself"):
        MODELS["ch-no-adhesion"].check_resolution(x, y)
    # near contact without crossing: two sheets a fraction of a chord apart
    xs, ys = paper_curve(200)
    assert self_intersections(xs, ys).shape == (0, 2)
    s = np.linspace(0, 1, 100, endpoint=False)
    bottom = np.column_stack([s, np.zeros_like(s)])
    top = np.column_stack([1 - s, np.full_like(s, 0.004)])  # closer than a chord (0.01)
    pts = np.vstack([bottom, top])
    assert self_intersections(pts[:, 0], pts[:, 1]).shape == (0, 2)
    top[50, 1] = -0.001  # one node pushed through the other sheet
    pts = np.vstack([bottom, top])
    assert self_intersections(pts[:, 0], pts[:, 1]).shape[0] == 2


@pytest.mark.parametrize("name", ["cha-neighbours", "cha-dense", "facet"])
def test_diverged_iterate_gives_nonfinite_residual_not_exception(name):
    sys = MODELS[name].setup(*paper_curve(32) if "cha" in name else smooth_curve(32))
    y = sys.y0.copy()
    y[3] = np.nan
    assert not np.all(np.isfinite(sys.residual(y, np.zeros(sys.size))))


def test_overflowing_iterate_gives_nonfinite_residual_without_warnings():
    sys = MODELS["facet"].setup(*smooth_curve(32))
    y = sys.y0.copy()
    y[sys.iL] = 1e200  # L**3 overflows
    F = sys.residual(y, np.zeros(sys.size))  # pytest turns qsa RuntimeWarnings into errors
    assert not np.all(np.isfinite(F))
    y = sys.y0.copy()
    y[2 * sys.N] = 1e200  # kappa^2 overflows
    assert not np.all(np.isfinite(sys.residual(y, np.zeros(sys.size))))
    J = sys.jacobian(y, np.zeros(sys.size), 1.0)
    assert not np.all(np.isfinite(J.data))


# --------------------------------------------------- local/nonlocal splitting
@pytest.mark.parametrize("name", ["cha-neighbours", "cha-dense", "facet"])
def test_jacobian_parts_sum_to_the_jacobian(name):
    sys = MODELS[name].setup(*paper_curve(60))
    rng = np.random.default_rng(1)
    yy = sys.y0 + 0.01 * rng.standard_normal(sys.size)
    yd = rng.standard_normal(sys.size)
    J = sys.jacobian(yy, yd, 7.0)
    for _ in range(2):  # second call: cached patterns
        Jl, Jn = sys.jacobian_parts(yy, yd, 7.0)
        assert abs(Jl + Jn - J).max() <= 1e-14 * abs(J).max()
        assert Jl.nnz < 60 * sys.N
    if name == "facet":
        assert Jn.nnz == 0
    else:
        assert Jn.nnz > 10 * sys.N  # the long-range kernel couples far nodes


def test_local_part_preconditions_gmres_for_the_long_range_kernel():
    import scipy.sparse.linalg as spla

    sys = CHA(**PAPER_CHA).setup(*paper_curve(200))
    k = 1e-3
    J = sys.jacobian(sys.y0, np.zeros(sys.size), 1 / k)
    Jl, _ = sys.jacobian_parts(sys.y0, np.zeros(sys.size), 1 / k)
    b = np.random.default_rng(0).standard_normal(sys.size)
    x_direct = splu(J).solve(b)
    lu = splu(Jl)
    M = spla.LinearOperator(J.shape, lu.solve)
    its = []
    x, info = spla.gmres(J, b, M=M, rtol=1e-12, restart=60, maxiter=5,
                         callback=lambda r: its.append(r), callback_type="pr_norm")
    assert info == 0 and len(its) <= 25
    assert np.max(np.abs(x - x_direct)) <= 1e-9 * np.max(np.abs(x_direct))
