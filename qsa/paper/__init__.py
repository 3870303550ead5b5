"""The paper's reproductions: scenarios, runs and comparisons, returning frozen results.

* :mod:`qsa.paper.scenarios` -- every reproduction's parameters and initial
  data: :class:`FacetScenario` (f:facet), :class:`CHAScenario` (Table T1,
  f:Snowflake, f:fold), :class:`ConvergenceScenario` (:data:`CONVERGENCE`, the
  appendix example) and the front-reduction polygons :class:`Scenario`
  (:data:`SCENARIOS`).
* :mod:`qsa.paper.runs` -- :func:`run_facet`, :func:`run_cha`,
  :func:`run_folding`, :func:`resolution_check`; :mod:`qsa.paper.appendix` --
  :func:`run_convergence` (Table ap:t1) and :func:`run_timesteps`.
* :mod:`qsa.paper.fronts` -- :func:`compare_fronts`: the front-position ODE
  against the DAE flow up to the first collision; :mod:`qsa.paper.eigenvalues` --
  :func:`compare_eigenvalues`: against the full linearization, mode by mode;
  :mod:`qsa.paper.coarsening` -- :func:`compare_coarsening`: through a whole
  coarsening (f:facet's, ``qsa reproduce coarsening``).

Results (:mod:`qsa.paper.results`) are frozen dataclasses with named fields;
``summary()`` gives the JSON that ``qsa reproduce NAME --json`` prints. The
library (:mod:`qsa.flows`, :mod:`qsa.reduction`, ...) never imports this package.

Examples
--------
>>> from qsa.paper import SCENARIOS, CONVERGENCE
>>> sorted(SCENARIOS), CONVERGENCE.rho
(['short-facet', 'triangle'], 1.5)
"""

from qsa.paper.appendix import (
    ConvergenceRun,
    ConvergenceStudy,
    StepCount,
    TimestepRun,
    run_convergence,
    run_timesteps,
)
from qsa.paper.coarsening import (
    CoarseningComparison,
    DAECoarsening,
    SequenceEvent,
    compare_coarsening,
    dae_coarsening,
)
from qsa.paper.fronts import (
    DAESpread,
    EigenvalueComparison,
    FrontComparison,
    VariableLengthComparison,
    compare_eigenvalues,
    compare_fronts,
)
from qsa.paper.results import (
    CHARun,
    Coarsening,
    CoarseningEvent,
    Crossing,
    FacetRun,
    FacetState,
    FoldingRun,
    ResolutionCheck,
    SelfIntersectionReport,
    coarsening_events,
)
from qsa.paper.runs import resolution_check, run_cha, run_facet, run_folding
from qsa.paper.scenarios import (
    CONVERGENCE,
    SCENARIOS,
    CHAScenario,
    ConvergenceScenario,
    FacetScenario,
    FoldBalance,
    Scenario,
    circle_balance_length,
    front_scenario,
    random_polygon,
    scenario_splice,
    spinodal_radius,
)

__all__ = [
    "FacetScenario", "CHAScenario", "FoldBalance", "ConvergenceScenario", "CONVERGENCE",
    "Scenario", "SCENARIOS", "front_scenario", "scenario_splice",
    "run_facet", "run_cha", "run_folding", "resolution_check", "run_convergence",
    "run_timesteps", "coarsening_events",
    "FacetRun", "FacetState", "CHARun", "FoldingRun", "ResolutionCheck", "Crossing",
    "SelfIntersectionReport", "Coarsening", "CoarseningEvent", "ConvergenceRun",
    "ConvergenceStudy", "StepCount", "TimestepRun",
    "compare_fronts", "compare_eigenvalues", "FrontComparison", "VariableLengthComparison",
    "DAESpread", "EigenvalueComparison", "compare_coarsening", "dae_coarsening",
    "CoarseningComparison", "DAECoarsening", "SequenceEvent", "random_polygon",
    "spinodal_radius", "circle_balance_length",
]
