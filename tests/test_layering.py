"""The pipeline's layers import one way (lower layers never import upper ones).

Every ``import`` statement of every module of ``qsa`` is read from its source
(module level and inside functions alike) and mapped to the top-level part of
``qsa`` it names.
"""

import ast
import functools
from pathlib import Path

import pytest

import qsa

ROOT = Path(qsa.__file__).parent

#: part -> parts it must never import
FORBIDDEN = {
    "energies": {"equilibria", "spectra", "flows", "continuation", "reduction", "plotting"},
    "equilibria": {"spectra", "flows", "continuation", "plotting"},
    "spectra": {"equilibria", "flows", "continuation", "plotting"},
    "flows": {"equilibria", "spectra", "continuation", "plotting"},
    "continuation": {"flows", "plotting"},
    "reduction": {"plotting"},
    "geometry": {"energies", "equilibria", "spectra", "flows", "continuation"},
    "constraints": {"energies", "equilibria", "spectra", "flows", "continuation"},
    "closure": {"geometry", "energies", "equilibria", "spectra", "flows", "continuation"},
    "curve": {"geometry", "energies", "equilibria", "spectra", "flows", "continuation"},
    "discretize": {"curve", "geometry", "energies", "equilibria", "spectra", "flows"},
    "measures": {"energies", "equilibria", "spectra", "flows", "continuation"},
    "polygon": {"discretize", "curve", "geometry", "energies", "equilibria", "spectra", "flows"},
    "plotting": set(),
}
# the paper's reproductions use the library, never the other way
for _parts in FORBIDDEN.values():
    _parts.add("paper")

#: modules kept only as deprecated aliases of a moved home
ALIASES = {"equilibria/continuation.py", "flows/scenarios.py", "flows/paper_runs.py",
           "reduction/compare.py"}


def _part(path: Path) -> str:
    rel = path.relative_to(ROOT)
    return rel.parts[0].removesuffix(".py")


def _imported_parts(path: Path) -> set:
    tree = ast.parse(path.read_text(), str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            if node.module == "qsa":  # from qsa import spectra
                names.update(f"qsa.{a.name}" for a in node.names)
    return {n.split(".")[1] for n in names if n.startswith("qsa.")}


@functools.lru_cache(maxsize=1)
def import_table() -> dict:
    """``{part: set of other parts it imports}`` over the package's modules."""
    table = {}
    for path in sorted(ROOT.rglob("*.py")):
        if str(path.relative_to(ROOT)) in ALIASES:
            continue
        part = _part(path)
        table.setdefault(part, set()).update(_imported_parts(path) - {part})
    return table


@pytest.mark.parametrize("part", sorted(FORBIDDEN))
def test_lower_layers_do_not_import_upper_ones(part):
    table = import_table()
    bad = table.get(part, set()) & FORBIDDEN[part]
    assert not bad, f"qsa.{part} imports {sorted(bad)}"


def test_the_parser_sees_imports():
    # a check of the check: the continuation uses both layers below it
    assert {"equilibria", "spectra", "energies"} <= import_table()["continuation"]


#: what a function of qsa may import inside its body: optional dependencies, and the
#: compiled kernels that need one (numba)
LAZY_ALLOWED = {"tqdm", "dask", "distributed", "numba", "qsa.reduction._kernels"}


def _function_imports(path: Path):
    tree = ast.parse(path.read_text(), str(path))
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for sub in ast.walk(node):
                if isinstance(sub, ast.Import):
                    yield from ((a.name, sub.lineno) for a in sub.names)
                elif isinstance(sub, ast.ImportFrom):
                    base = "." * sub.level + (sub.module or "")
                    if base == "qsa.reduction":  # from qsa.reduction import _kernels
                        yield from ((f"{base}.{a.name}", sub.lineno) for a in sub.names)
                    else:
                        yield base, sub.lineno


def test_imports_sit_at_module_top():
    """Except optional dependencies and the command line's lazy loading of subcommands."""
    bad = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT)
        if rel.parts[0] == "commands" or rel.name == "cli.py":
            continue
        for name, line in _function_imports(path):
            if not any(name == a or name.startswith(a + ".") for a in LAZY_ALLOWED):
                bad.append(f"qsa/{rel}:{line} imports {name}")
    assert not bad, "\n".join(bad)


def test_no_test_module_imports_another():
    """Shared test code lives in tests/helpers.py, tests/reference/ and conftest.py."""
    tests = Path(__file__).parent
    bad = []
    for path in sorted(tests.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                if name.startswith("tests.") and not (
                        name == "tests.helpers" or name.startswith("tests.reference")):
                    bad.append(f"{path.relative_to(tests)}:{node.lineno} imports {name}")
    assert not bad, "\n".join(bad)
