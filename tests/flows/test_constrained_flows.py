"""Length- and area-preserving flows: exact Jacobian, conservation, dissipation, equilibria."""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.constraints import FixedArea, FixedLength
from qsa.energies import CanhamHelfrich
from qsa.equilibria import polish
from qsa.flows import CHA, FacetingFlow, solve_flow
from qsa.flows.models.constrained import polygon_area
from tests.helpers import FLOW_MODELS as MODELS
from tests.helpers import fitted_order, numerical_jacobians, paper_curve, smooth_curve

CONSTRAINTS = {
    "length": [FixedLength()],
    "area": [FixedArea()],
    "both": [FixedArea(), FixedLength()],
}


@pytest.mark.parametrize("cname", CONSTRAINTS)
@pytest.mark.parametrize("name", ["cha-neighbours", "ch-no-adhesion", "facet"])
def test_jacobian_matches_central_differences(name, cname):
    x, y = paper_curve(24)
    sys = MODELS[name].setup(x, y, constraints=CONSTRAINTS[cname])
    m = len(CONSTRAINTS[cname])
    assert sys.size == MODELS[name].setup(x, y).size + m
    rng = np.random.default_rng(7)
    yy = sys.y0 + 0.05 * rng.standard_normal(sys.size) * (1 + np.abs(sys.y0))
    yd = rng.standard_normal(sys.size)
    Jy, Jd = numerical_jacobians(sys, yy, yd)
    c = 2.7
    Ac = sys.jacobian(yy, yd, c).toarray()
    assert np.max(np.abs(Ac - (Jy + c * Jd))) <= 1e-6 * np.max(np.abs(Jy + c * Jd))
    Jl, Jn = sys.jacobian_parts(yy, yd, c)
    assert np.max(np.abs((Jl + Jn).toarray() - Ac)) <= 1e-12 * np.max(np.abs(Ac))


@pytest.mark.parametrize("name", ["cha-neighbours", "facet"])
def test_initial_state_is_consistent_and_its_velocity_conserves(name):
    x, y = smooth_curve(64)
    sys = MODELS[name].setup(x, y, constraints=[FixedLength(), FixedArea()])
    u = sys.unpack(sys.y0)
    algebraic = np.setdiff1d(np.arange(sys.size), sys.differential_rows)
    F = sys.residual(sys.y0, np.zeros(sys.size))
    assert np.max(np.abs(F[algebraic])) < 1e-8 * np.max(np.abs(sys.y0))
    with pytest.raises(ValueError, match="index 2"):
        sys.time_derivative(sys.y0)
    # the initial multipliers project V onto {int kappa V = int V = 0}
    assert abs(np.sum(u["V"])) < 1e-10 * np.sum(np.abs(u["V"]))
    assert abs(np.sum(u["kappa"] * u["V"])) < 1e-10 * np.sum(np.abs(u["kappa"] * u["V"]))
    assert [k.target for k in sys.constraints] == [u["L"], polygon_area(x, y)]
    assert sys.metadata()["constraints"][1] == {"constraint": "FixedArea",
                                                "A": polygon_area(x, y)}


def _trefoil(n=400):
    th = 2 * np.pi * np.arange(n) / n
    r = 1 + 0.2 * np.cos(3 * th)
    return r * np.cos(th), r * np.sin(th)


@pytest.mark.parametrize("model", [CHA(eps=0.1, beta=1.0, rho=1.2),
                                   FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0)],
                         ids=["cha", "facet"])
@pytest.mark.parametrize("cname", CONSTRAINTS)
def test_constrained_flows_conserve_and_dissipate(model, cname):
    free = solve_flow(model, _trefoil(), 0.05, N=64, tol=1e-4)
    res = solve_flow(model, _trefoil(), 0.05, N=64, tol=1e-4, constraints=CONSTRAINTS[cname])
    assert res.success and free.success, res.message
    A, L = res.areas(), res.length
    if cname in ("area", "both"):
        # exact up to the Newton tolerance (1e-2 tol on the positions) times the length
        assert np.max(np.abs(A - A[0])) <= 2 * 1e-2 * 1e-4 * L[0]
    if cname in ("length", "both"):
        assert np.max(np.abs(L - L[0])) <= 1e-12 * L[0]
    # the free flow moves what the constrained one keeps
    assert abs(free.areas()[-1] - A[0]) > 1e-3 and abs(free.length[-1] - L[0]) > 1e-3
    assert np.all(np.diff(res.energy_steps) <= 1e-10 * res.energy_steps[0])
    assert res.energy[-1] < res.energy[0]


def ellipse(grid, a=1.25, b=0.8):
    return Curve.polar(lambda t: a * b / np.sqrt((b * np.cos(t)) ** 2 + (a * np.sin(t)) ** 2),
                       grid)


def test_vesicle_flow_reaches_the_polished_equilibrium_at_order_two():
    """Canham-Helfrich at fixed length and area from an ellipse: the stationary state is the
    polished constrained equilibrium (energy to O(h^2), the same multipliers mu_L, mu_A)."""
    x, y = ellipse(Fourier(257)).positions()
    Ns, errs = [64, 128, 256], []
    for N in Ns:
        res = solve_flow(CHA(eps=1.0, beta=0.0, rho=1.0), (x, y), 0.5, N=N, tol=1e-5,
                         constraints=[FixedLength(), FixedArea()])
        assert res.success, res.message
        assert np.abs(res.system.normal_velocity(res.states[-1])).max() < 1e-8
        ref = polish(CanhamHelfrich(1.0), ellipse(Fourier(129)),
                     constraints=[FixedLength(res.length[-1]), FixedArea(res.areas()[-1])])
        assert ref.success, ref.message
        errs.append(abs(res.energy[-1] - ref.energy.energy(ref.curve)))
        mu = res.system.unpack(res.states[-1])["multipliers"]
        assert mu == pytest.approx(ref.constraint_multipliers, rel=0.02)
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_resume_continues_a_constrained_run_exactly(tmp_path):
    model = CHA(eps=0.1, beta=1.0, rho=1.2)
    cons = [FixedArea()]
    full = solve_flow(model, _trefoil(), 0.02, N=48, tol=1e-4, constraints=cons)
    path = tmp_path / "run.npz"
    part = solve_flow(model, _trefoil(), 0.02, N=48, tol=1e-4, constraints=cons,
                      checkpoint=path, checkpoint_interval=0.0,
                      callback=lambda t, y, s: t > 0.005)
    assert part.status == 1
    rest = solve_flow(model, None, 0.02, resume=path)
    assert rest.system.constraints == part.system.constraints
    assert np.allclose(rest.states[-1], full.states[-1], rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="checkpoint was written with"):
        solve_flow(model, None, 0.02, resume=path, constraints=[FixedLength()])


def test_bad_constraints_raise():
    model = CHA(eps=0.1, beta=1.0, rho=1.2)
    with pytest.raises(ValueError, match="keeps the initial value"):
        solve_flow(model, _trefoil(), 0.01, N=32, constraints=[FixedArea(1.0)])
    with pytest.raises(ValueError, match="given twice"):
        solve_flow(model, _trefoil(), 0.01, N=32, constraints=[FixedArea(), FixedArea()])

    class Plain(CHA):
        def setup(self, x, y):
            return super().setup(x, y)

    with pytest.raises(ValueError, match="does not support"):
        solve_flow(Plain(eps=0.1, beta=1.0, rho=1.2), _trefoil(), 0.01, N=32,
                   constraints=[FixedLength()])
