"""The paper wing's old import paths keep working; the library never imports qsa.paper."""

import ast
import pathlib
import subprocess
import sys

import qsa.paper as paper

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_old_names_are_aliases_of_qsa_paper():
    import qsa.flows.paper_runs as paper_runs
    import qsa.flows.scenarios as scenarios
    import qsa.reduction as reduction
    import qsa.reduction.compare as compare

    assert reduction.compare_fronts is paper.compare_fronts
    assert reduction.compare_eigenvalues is paper.compare_eigenvalues
    assert reduction.SCENARIOS is paper.SCENARIOS
    assert compare.scenario_splice is paper.scenario_splice
    assert compare.Scenario is paper.Scenario and compare.FrontComparison is paper.FrontComparison
    assert scenarios.CHAScenario is paper.CHAScenario
    assert scenarios.FacetScenario is paper.FacetScenario
    for name in ("run_facet", "run_cha", "resolution_check", "coarsening_events"):
        assert getattr(paper_runs, name) is getattr(paper, name)
    for module in (paper_runs, scenarios, compare):
        assert all(hasattr(module, n) for n in module.__all__)
    assert all(hasattr(reduction, n) for n in reduction.__all__)


def test_command_aliases_of_the_appendix_numbers():
    from qsa.commands import reproduce_convergence, reproduce_timesteps

    assert reproduce_convergence.PAPER == paper.CONVERGENCE.paper_differences
    assert reproduce_convergence.PARAMS == paper.CONVERGENCE.model_params()
    x, _ = reproduce_convergence.paper_initial_curve(100)
    assert x.size == 100
    assert reproduce_timesteps.PAPER == paper.CONVERGENCE.paper_steps


def test_library_does_not_import_the_paper():
    code = ("import sys, qsa, qsa.flows, qsa.reduction, qsa.equilibria, qsa.spectra, "
            "qsa.energies, qsa.flows.analysis, qsa.plotting.simulations, qsa.plotting.fronts; "
            "print([m for m in sys.modules if m.startswith('qsa.paper')])")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_no_command_imports_another_command():
    for path in sorted((ROOT / "qsa" / "commands").glob("reproduce_*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith("qsa.commands.reproduce"), (path.name,
                                                                              node.module)
