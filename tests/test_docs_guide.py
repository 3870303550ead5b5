"""The examples of the user guide (docs/guide/*.md) run as printed, and its links resolve.

The ``python`` blocks of a page run in order in one namespace, as a reader would run
them in one session. A block whose first line is ``# slow`` runs only with
``-m slow``; no later block of its page may depend on it.
"""

import importlib
import re
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"
PAGES = sorted(p for p in GUIDE.glob("*.md") if p.name != "index.md")
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
ROLE = re.compile(r"\{(func|class|meth|mod|data|attr)\}`~?([\w.]+)`")


def blocks(page):
    return BLOCK.findall(page.read_text())


def run_page(page, tmp_path, monkeypatch, slow):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    env = {"__name__": "__guide__"}
    for i, code in enumerate(blocks(page)):
        if code.startswith("# slow") and not slow:
            continue
        exec(compile(code, f"{page.name}[block {i}]", "exec"), env)  # noqa: S102


def test_every_stage_has_a_page():
    names = {p.stem for p in PAGES}
    assert {"curves", "energies", "equilibria", "spectra", "flows", "reduction", "sweeps",
            "cli"} <= names
    toc = (GUIDE / "index.md").read_text()
    assert all(f"\n{name}\n" in toc for name in names), "a page is missing from the toctree"
    assert all(blocks(p) for p in PAGES), "every page has examples"


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_examples_run(page, tmp_path, monkeypatch):
    run_page(page, tmp_path, monkeypatch, slow=False)


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if any(b.startswith("# slow")
                                                          for b in blocks(p))],
                         ids=lambda p: p.stem)
def test_examples_run_with_slow_ones(page, tmp_path, monkeypatch):
    run_page(page, tmp_path, monkeypatch, slow=True)


def documented():
    """Dotted names of the objects docs/api.md gives a page (autosummary with a toctree).

    A module listed only as a section (``currentmodule``) has no page: link its
    section, ``[`qsa.energies`](../api.md#qsaenergies)``, instead of ``{mod}``.
    """
    names, module, toctree = set(), None, False
    for line in (ROOT / "docs" / "api.md").read_text().splitlines():
        head = re.fullmatch(r"\.\. currentmodule:: ([\w.]+)", line.strip())
        if head:
            module = head.group(1)
        elif line.strip().startswith(".. autosummary::"):
            toctree = False
        elif line.strip() == ":toctree: _generated":
            toctree = True
        elif toctree and re.fullmatch(r"   [\w.]+", line):
            names.add(f"{module}.{line.strip()}")
    return names


@pytest.mark.parametrize("page", sorted(GUIDE.glob("*.md")), ids=lambda p: p.stem)
def test_roles_name_documented_objects(page):
    """Each ``{func}`` ... role names an object of the API reference (or its member)."""
    known = documented()
    for role, target in ROLE.findall(page.read_text()):
        parts = target.split(".")
        # the longest documented prefix; the rest must be attributes of it
        cut = next((k for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in known), 0)
        assert cut, f"{page.name}: {{{role}}}`{target}` is not in docs/api.md"
        assert role not in ("func", "class", "mod", "data") or cut == len(parts), \
            f"{page.name}: {{{role}}}`{target}`: only {'.'.join(parts[:cut])} is documented"
        obj = resolve(parts)
        assert obj is not None, f"{page.name}: {{{role}}}`{target}` does not exist"
    sections = re.findall(r"^## `([\w.]+)`", (ROOT / "docs" / "api.md").read_text(), re.M)
    for anchor in re.findall(r"\(\.\./api\.md#([\w-]+)\)", page.read_text()):
        assert anchor in {m.replace(".", "") for m in sections}, f"{page.name}: #{anchor}"


def resolve(parts):
    """The object of a dotted name: the longest importable module, then attributes."""
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            obj = getattr(obj, name, None)
        return obj
    return None
