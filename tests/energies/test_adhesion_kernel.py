"""Kernel-level adhesion: e:LJ and its derivatives, cutoff, neighbour lists, fields."""

import math

import numpy as np
import pytest

from qsa.energies.adhesion import (
    AdhesionKernel,
    adhesion_energy,
    adhesion_field_jacobians,
    adhesion_fields,
    adhesion_pair_derivatives,
    adhesion_pairs,
    dense_pairs,
    pair_list,
)
from qsa.paper import CONVERGENCE, CHAScenario

PAPER_CHA = CONVERGENCE.model().kernel  # appendix convergence study
PAPER_FOLD = CHAScenario.literal().model().kernel  # Table T1 read literally: the shortest kernel


def wobbly_curve(N, amp=0.35, k=3, scale=1.0, seed=None):
    th = 2 * np.pi * np.arange(N) / N
    r = 1 + amp * np.cos(k * th)
    x = scale * (r * np.cos(th) + 0.05 * np.sin(4 * th))
    y = scale * r * np.sin(th)
    if seed is not None:
        rng = np.random.default_rng(seed)
        x = x + 1e-3 * scale * rng.standard_normal(N)
        y = y + 1e-3 * scale * rng.standard_normal(N)
    return x, y


def crenellated(N, folds=13, depth=0.12):
    """A 13-fold crenellated curve of length ~7-8 (the snowflake start, Table T1 scale)."""
    th = 2 * np.pi * np.arange(N) / N
    r = 1 + depth * np.tanh(4 * np.cos(folds * th))
    return r * np.cos(th), r * np.sin(th)


# ---------------------------------------------------------------- kernel
@pytest.mark.parametrize("kernel", [PAPER_CHA, PAPER_FOLD, AdhesionKernel(2.0, 0.3, 0.7)])
def test_kernel_derivatives_match_central_differences(kernel):
    s = kernel.l_star**2
    l = np.linspace(0.0, 12 * s, 37)[1:]
    d = 1e-6 * s
    fd1 = (kernel.A(l + d) - kernel.A(l - d)) / (2 * d)
    fd2 = (kernel.dA(l + d) - kernel.dA(l - d)) / (2 * d)
    assert np.max(np.abs(fd1 - kernel.dA(l))) <= 1e-7 * np.max(np.abs(kernel.dA(l)))
    assert np.max(np.abs(fd2 - kernel.d2A(l))) <= 1e-7 * np.max(np.abs(kernel.d2A(l)))


@pytest.mark.parametrize("a", [0.5, 1.0, 2.0])
def test_kernel_shape(a):
    k = AdhesionKernel(A0=3.0, l_star=0.2, a=a)
    assert k.A(0.0) == pytest.approx(3.0)
    lmin = k.minimum_distance**2
    assert lmin == pytest.approx(0.04 * (1 + a * a))
    assert abs(k.dA(lmin)) < 1e-12 * 3.0 / 0.04
    assert k.A(lmin) == pytest.approx(-3.0 / a**2 * math.exp(-1 - a * a), rel=1e-13)
    # sign change at |d| = a l*
    assert k.A((0.99 * a * 0.2) ** 2) > 0 > k.A((1.01 * a * 0.2) ** 2)
    assert k.pair_separation == pytest.approx(0.2 * math.sqrt(a * a + 0.5))


@pytest.mark.parametrize("kernel", [PAPER_CHA, PAPER_FOLD])
@pytest.mark.parametrize("rel", [1e-16, 1e-10])
def test_cutoff_bounds_the_tail_and_is_tight(kernel, rel):
    rc = kernel.cutoff_distance(rel)
    assert 5.0 < rc / kernel.l_star < 7.5
    r = rc * np.linspace(1.0, 3.0, 200)
    assert np.all(np.abs(kernel.A(r * r)) <= rel * kernel.A0 * (1 + 1e-9))
    assert np.all(np.abs(kernel.dA(r * r)) <= rel * kernel.A0 * (1 + 1e-9))
    r_in = 0.97 * rc
    assert max(abs(kernel.A(r_in**2)), abs(kernel.dA(r_in**2))) > rel * kernel.A0


def test_kernel_rejects_bad_parameters():
    for bad in [dict(A0=-1.0, l_star=0.5, a=1.0), dict(A0=1.0, l_star=0.0, a=1.0),
                dict(A0=1.0, l_star=0.5, a=float("nan")), dict(A0="x", l_star=0.5, a=1.0)]:
        name = [k for k, v in bad.items() if not (isinstance(v, float) and v > 0)][0]
        with pytest.raises(ValueError, match=name):
            AdhesionKernel(**bad)
    with pytest.raises(ValueError, match="rel"):
        PAPER_CHA.cutoff_distance(0.0)


# ------------------------------------------------------------- pair lists
def test_pair_list_equals_brute_force():
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0, 1, 300), rng.uniform(0, 1, 300)
    i, j = pair_list(x, y, 0.1)
    assert np.all(i < j)
    di, dj = dense_pairs(300)
    close = np.hypot(x[di] - x[dj], y[di] - y[dj]) <= 0.1
    found = set(zip(i.tolist(), j.tolist(), strict=True))
    assert found == set(zip(di[close].tolist(), dj[close].tolist(), strict=True))


def test_pair_list_rejects_bad_input():
    with pytest.raises(ValueError, match="NaN"):
        pair_list(np.array([0.0, np.nan]), np.zeros(2), 1.0)
    with pytest.raises(ValueError, match="cutoff"):
        pair_list(np.zeros(3), np.zeros(3), -1.0)
    with pytest.raises(ValueError, match="method"):
        adhesion_pairs(PAPER_CHA, np.zeros(3), np.zeros(3), method="fast")


# --------------------------------------------------------- dense vs list
@pytest.mark.parametrize(
    "kernel, curve",
    [
        (PAPER_CHA, lambda: wobbly_curve(200, scale=1.3, seed=1)),
        (PAPER_FOLD, lambda: crenellated(1200)),
        (AdhesionKernel(5.0, 0.05, 1.0), lambda: wobbly_curve(400, amp=0.45, k=5, seed=2)),
    ],
)
def test_neighbour_list_matches_dense(kernel, curve):
    x, y = curve()
    N = x.size
    L = np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y))
    w = L / N
    assert w < kernel.l_star  # resolved
    pn = adhesion_pairs(kernel, x, y, method="neighbours")
    assert pn[0].size < N * (N - 1) // 2 or kernel is PAPER_CHA
    Bd, Fd = adhesion_fields(kernel, x, y, w, method="dense")
    Bn, Fn = adhesion_fields(kernel, x, y, w, pairs=pn)
    assert np.max(np.abs(Bn - Bd)) <= 1e-12 * np.max(np.abs(Bd))
    assert np.max(np.abs(Fn - Fd)) <= 1e-12 * np.max(np.abs(Fd))
    Ed = adhesion_energy(kernel, x, y, w, method="dense")
    En = adhesion_energy(kernel, x, y, w, pairs=pn)
    assert abs(En - Ed) <= 1e-12 * abs(Ed)


def test_short_kernel_uses_few_pairs():
    x, y = crenellated(1200)
    i, _ = adhesion_pairs(PAPER_FOLD, x, y)
    assert i.size < 30 * 1200  # O(N), not N^2/2 = 7.2e5


# ------------------------------------------------- fields are derivatives
def _random_setup(N=40, seed=0):
    x, y = wobbly_curve(N, scale=1.2, seed=seed)
    rng = np.random.default_rng(seed)
    w = 0.2 * (1 + 0.3 * rng.uniform(size=N))  # non-uniform weights on purpose
    return x, y, w


@pytest.mark.parametrize("method", ["dense", "neighbours"])
def test_force_is_position_gradient_and_B_is_weight_gradient(method):
    k = PAPER_CHA
    x, y, w = _random_setup()
    B, F = adhesion_fields(k, x, y, w, method=method)
    d = 1e-6
    gx = np.empty_like(x)
    gy = np.empty_like(x)
    gw = np.empty_like(x)
    for n in range(x.size):
        e = np.zeros_like(x)
        e[n] = d
        # fixed pairs so the neighbour list cannot change between the two evaluations
        gx[n] = (adhesion_energy(k, x + e, y, w, method="dense")
                 - adhesion_energy(k, x - e, y, w, method="dense")) / (2 * d)
        gy[n] = (adhesion_energy(k, x, y + e, w, method="dense")
                 - adhesion_energy(k, x, y - e, w, method="dense")) / (2 * d)
        gw[n] = (adhesion_energy(k, x, y, w + e, method="dense")
                 - adhesion_energy(k, x, y, w - e, method="dense")) / (2 * d)
    scale = np.max(np.abs(w * F[:, 0]))
    assert np.max(np.abs(gx - w * F[:, 0])) <= 1e-7 * scale
    assert np.max(np.abs(gy - w * F[:, 1])) <= 1e-7 * scale
    assert np.max(np.abs(gw - B)) <= 1e-7 * np.max(np.abs(B))


def test_field_jacobians_match_central_differences():
    k = AdhesionKernel(A0=10.0, l_star=0.3, a=1.0)
    x, y, w = _random_setup(N=30, seed=4)
    N = x.size
    pairs = dense_pairs(N)
    JB, JF = adhesion_field_jacobians(k, x, y, w, pairs=pairs)
    JB, JF = JB.toarray(), JF.toarray()
    d = 1e-6
    JBn = np.zeros_like(JB)
    JFn = np.zeros_like(JF)
    for c in range(2 * N):
        e = np.zeros(2 * N)
        e[c] = d
        Bp, Fp = adhesion_fields(k, x + e[:N], y + e[N:], w, pairs=pairs)
        Bm, Fm = adhesion_fields(k, x - e[:N], y - e[N:], w, pairs=pairs)
        JBn[:, c] = (Bp - Bm) / (2 * d)
        JFn[:, c] = np.concatenate([Fp[:, 0] - Fm[:, 0], Fp[:, 1] - Fm[:, 1]]) / (2 * d)
    assert np.max(np.abs(JB - JBn)) <= 1e-7 * np.max(np.abs(JBn))
    assert np.max(np.abs(JF - JFn)) <= 1e-7 * np.max(np.abs(JFn))
    # the force is a gradient (w_i force_i = dE/dX_i): W JF is symmetric
    W = np.concatenate([w, w])[:, None]
    assert np.max(np.abs(W * JF - (W * JF).T)) <= 1e-12 * np.max(np.abs(W * JF))


def test_pair_derivatives_fields():
    k = PAPER_CHA
    x, y, _ = _random_setup(N=20)
    t = adhesion_pair_derivatives(k, x, y, method="dense")
    l = t.dx**2 + t.dy**2
    assert np.allclose(t.dA, k.dA(l), rtol=1e-14, atol=0)
    assert np.allclose(t.hxy, 2 * k.d2A(l) * t.dx * t.dy, rtol=1e-13, atol=0)
    assert np.allclose(t.hxx - t.hyy, 2 * k.d2A(l) * (t.dx**2 - t.dy**2), rtol=1e-12, atol=1e-12)


def test_long_range_kernel_takes_every_pair_without_a_tree():
    x, y = wobbly_curve(50)
    i, j = pair_list(x, y, 100.0)
    di, dj = dense_pairs(50)
    assert np.array_equal(i, di) and np.array_equal(j, dj)


def test_rigid_invariance_total_force_and_torque_vanish():
    # Translation and rotation invariance of the discrete energy (Conventions, section 6):
    # sum_i w_i force_i = 0 and sum_i w_i X_i x force_i = 0, exactly (round-off).
    x, y, w = _random_setup(N=60, seed=7)
    B, F = adhesion_fields(PAPER_CHA, x, y, w, method="dense")
    scale = np.sum(w * np.hypot(F[:, 0], F[:, 1])) * (1 + np.max(np.hypot(x, y)))
    assert abs(np.sum(w * F[:, 0])) <= 1e-13 * scale
    assert abs(np.sum(w * F[:, 1])) <= 1e-13 * scale
    assert abs(np.sum(w * (x * F[:, 1] - y * F[:, 0]))) <= 1e-13 * scale


def test_B_includes_the_diagonal_and_isolated_node():
    # Two far-apart nodes: B_i = 2 A0 w_i (self term only), no force.
    k = PAPER_FOLD
    B, F = adhesion_fields(k, np.array([0.0, 10.0]), np.array([0.0, 0.0]), np.array([0.1, 0.2]))
    assert np.allclose(B, [2 * 40.0 * 0.1, 2 * 40.0 * 0.2], rtol=1e-14)
    assert np.all(F == 0)
    E = adhesion_energy(k, np.array([0.0, 10.0]), np.array([0.0, 0.0]), np.array([0.1, 0.2]))
    assert E == pytest.approx(40.0 * (0.01 + 0.04), rel=1e-14)


def test_parallel_strands_optimal_separation():
    # Two long parallel strands at distance D: the normal force on a strand vanishes at
    # D = l* sqrt(a^2 + 1/2) (Conventions, section 6), attraction beyond, repulsion inside.
    k = AdhesionKernel(A0=1.0, l_star=0.05, a=1.0)
    h = 0.004
    s = np.arange(-1.0, 1.0, h)

    def force_y(D):
        x = np.concatenate([s, s])
        y = np.concatenate([np.zeros_like(s), np.full_like(s, D)])
        _, F = adhesion_fields(k, x, y, h)
        return F[s.size // 2, 1]  # middle node of the lower strand, along +y

    from scipy.optimize import brentq

    D0 = brentq(force_y, 0.5 * k.l_star, 3 * k.l_star, xtol=1e-12)
    assert D0 == pytest.approx(k.pair_separation, rel=1e-3)
    # force = energy gradient: inside, moving the lower strand up (closer) raises the
    # energy (repulsion); beyond D0 it lowers it (adhesion).
    assert force_y(0.8 * D0) > 0 > force_y(1.2 * D0)


@pytest.mark.parametrize("cutoff", [0.05, 0.6, 1.5, 5.0])
def test_pair_list_paths_agree(cutoff):
    # tree, filtered all-pairs and all-pairs paths return the same sorted pair set
    x, y = wobbly_curve(300, seed=9)
    i, j = pair_list(x, y, cutoff)
    di, dj = dense_pairs(300)
    keep = np.hypot(x[di] - x[dj], y[di] - y[dj]) <= cutoff
    assert np.array_equal(i, di[keep]) and np.array_equal(j, dj[keep])


def test_uniform_and_general_weight_paths_agree():
    from qsa.energies.adhesion import uniform_weight_fields

    x, y = wobbly_curve(120, seed=3)
    i, j = dense_pairs(120)
    B1, F1 = uniform_weight_fields(PAPER_CHA, x, y, 0.07, i, j)
    w = np.full(120, 0.07)
    w[0] *= 1 + 1e-15  # forces the general path
    B2, F2 = adhesion_fields(PAPER_CHA, x, y, w, pairs=(i, j))
    assert np.max(np.abs(B1 - B2)) <= 1e-12 * np.max(np.abs(B1))
    assert np.max(np.abs(F1 - F2)) <= 1e-12 * np.max(np.abs(F1))


@pytest.mark.parametrize("kernel", [PAPER_CHA, AdhesionKernel(A0=3.0, l_star=0.15, a=0.8)])
def test_rigid_invariance_identities_on_a_closed_curve(kernel):
    # Conventions and errata, section 6: int (force.n + kappa B)(v0.n) dsigma = 0 and
    # int (force.n + kappa B)(gamma.tau) dsigma = 0, on a smooth non-symmetric closed
    # curve with exact normals/curvature and spectrally accurate trapezoid weights.
    from qsa.energies.adhesion import adhesion_normal_velocity

    N = 600
    t = 2 * np.pi * np.arange(N) / N
    r = 1 + 0.2 * np.cos(3 * t) + 0.1 * np.sin(2 * t + 0.3)
    rp = -0.6 * np.sin(3 * t) + 0.2 * np.cos(2 * t + 0.3)
    rpp = -1.8 * np.cos(3 * t) - 0.4 * np.sin(2 * t + 0.3)
    x, y = r * np.cos(t), r * np.sin(t)
    xp, yp = rp * np.cos(t) - r * np.sin(t), rp * np.sin(t) + r * np.cos(t)
    speed = np.hypot(xp, yp)
    kappa = (r**2 + 2 * rp**2 - r * rpp) / speed**3
    tx, ty = xp / speed, yp / speed
    nx, ny = ty, -tx
    w = speed * 2 * np.pi / N  # dsigma weights (parameter t in [0, 2 pi))
    V = adhesion_normal_velocity(kernel, x, y, nx, ny, kappa, w, method="dense")
    scale = np.sum(np.abs(V) * w)
    for f in (nx, ny, x * tx + y * ty):
        assert abs(np.sum(V * f * w)) <= 1e-10 * scale
    # and it is not trivially small
    assert scale > 1e-3 * kernel.A0


@pytest.mark.parametrize("a", [0.6, 1.0, 1.5])
@pytest.mark.parametrize("D", [0.3, 0.9, 1.2, 2.0])
def test_parallel_strands_force_and_B_closed_forms(a, D):
    # Two straight strands y = 0 and y = D l*. With L = l*, the integrals of the Gaussian
    # kernel along a strand give, at a node of the lower strand (D in units of l*):
    #   force . e_y = -4 sqrt(pi) (A0 / a^2) D exp(-D^2) (D^2 - a^2 - 1/2),
    #   B = 2 sqrt(pi) A0 l* [(1 - 1/(2 a^2)) + exp(-D^2) (1 - D^2/a^2 - 1/(2 a^2))].
    # The trapezoid rule is spectrally accurate for the Gaussian, so the discrete fields
    # match to round-off once the strands are long compared with l*.
    A0, l_star = 3.0, 0.05
    k = AdhesionKernel(A0=A0, l_star=l_star, a=a)
    h = l_star / 8
    s = h * np.arange(-320, 321)  # 40 l* either side of the middle node
    x = np.concatenate([s, s])
    y = np.concatenate([np.zeros_like(s), np.full_like(s, D * l_star)])
    B, F = adhesion_fields(k, x, y, h)
    mid = s.size // 2
    e = np.exp(-D**2)
    force = -4 * np.sqrt(np.pi) * (A0 / a**2) * D * e * (D**2 - a**2 - 0.5)
    b = 2 * np.sqrt(np.pi) * A0 * l_star * ((1 - 0.5 / a**2) + e * (1 - D**2 / a**2 - 0.5 / a**2))
    assert F[mid, 1] == pytest.approx(force, rel=1e-10, abs=1e-12 * A0 / l_star)
    assert abs(F[mid, 0]) < 1e-12 * A0 / l_star  # symmetric about the middle node
    assert B[mid] == pytest.approx(b, rel=1e-10)


def test_fields_at_the_last_curve_are_reused_as_computed():
    from qsa import Curve, FiniteDifference
    from qsa.energies import Adhesion

    E = Adhesion(A0=10.0, l_star=0.3, a=1.0)
    c1 = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(90))
    c2 = Curve.polar(lambda t: 1 + 0.25 * np.cos(3 * t), FiniteDifference(90))
    for c in (c1, c2, c1):
        B, force = E.fields(c)
        x, y = c.positions()
        B0, force0 = adhesion_fields(E.kernel, x, y, c.dsigma)
        assert np.array_equal(B, B0) and np.array_equal(force, force0)
        B[:] = 0.0  # the caller's copy: the next call is unaffected
        force[:] = 0.0
        assert np.array_equal(E.fields(c)[0], B0)


def test_neighbour_list_at_the_last_positions_is_reused_as_computed():
    k = AdhesionKernel(A0=1.0, l_star=0.05, a=1.0)
    x1, y1 = wobbly_curve(300)
    x2, y2 = wobbly_curve(300, amp=0.3)
    for x, y in ((x1, y1), (x2, y2), (x1, y1)):
        i, j = adhesion_pairs(k, x, y)
        i0, j0 = pair_list(x, y, k.cutoff_distance(1e-16))
        assert np.array_equal(i, i0) and np.array_equal(j, j0)
        i[:] = 0  # the caller's copy: the next call is unaffected
        assert np.array_equal(adhesion_pairs(k, x, y)[0], i0)


def test_neighbour_lists_of_moved_nodes_equal_fresh_queries():
    """A curve moved by less than the kept margin gets its list by filtering the kept wider
    one: the same pairs in the same order as a fresh k-d tree query; a larger move queries."""
    from qsa.energies import adhesion as ad

    k = ad.AdhesionKernel(A0=1.0, l_star=0.05, a=1.0)
    t = 2 * np.pi * np.arange(600) / 600
    x, y = np.cos(t) * (1 + 0.3 * np.cos(5 * t)), np.sin(t) * (1 + 0.3 * np.cos(5 * t))
    cutoff = k.cutoff_distance()
    rng = np.random.default_rng(0)
    ad._SUPERSETS.clear()
    base = ad.adhesion_pairs(k, x, y)
    assert len(ad._SUPERSETS) == 1
    for scale in (1e-12, 1e-6, 0.2 * ad._MARGIN * cutoff, 0.05):
        xm, ym = x + scale * rng.standard_normal(600), y + scale * rng.standard_normal(600)
        got = ad.adhesion_pairs(k, xm, ym)
        fresh = ad.pair_list(xm, ym, cutoff)
        assert np.array_equal(got[0], fresh[0]) and np.array_equal(got[1], fresh[1])
    assert len(ad._SUPERSETS) == 2  # the large move made (and kept) a list of its own
    again = ad.adhesion_pairs(k, x + 1e-13, y)
    assert np.array_equal(again[0], base[0]) and np.array_equal(again[1], base[1])
