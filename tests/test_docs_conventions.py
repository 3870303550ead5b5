"""The "Conventions and errata" page (docs/conventions.md) has what the code cites from it.

Docstrings and comments across qsa cite "Conventions and errata, section N"; each such
section must be a numbered heading of the page. The page names the tests that guard
each convention and erratum (``tests/...py::test_name``); each must be defined there.
"""

import re
from pathlib import Path

from tests.helpers import undefined_tests

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "conventions.md"
# the phrase may be wrapped across lines, also inside ``#`` comments
CITATION = re.compile(r"Conventions and errata,\s*(?:#\s*)?section\s+(\d+)")


def page_sections():
    """``{N: title}`` of the page's ``## N. Title`` headings."""
    return {int(m.group(1)): m.group(2)
            for m in re.finditer(r"^## (\d+)\. (.+)$", PAGE.read_text(), re.M)}


def cited_sections():
    """``{N: [files citing section N]}`` over the qsa package."""
    out = {}
    for path in sorted((ROOT / "qsa").rglob("*.py")):
        for m in CITATION.finditer(path.read_text()):
            out.setdefault(int(m.group(1)), []).append(str(path.relative_to(ROOT)))
    return out


def test_title_and_numbered_sections():
    text = PAGE.read_text()
    assert text.splitlines()[0] == "# Conventions and errata"
    assert sorted(page_sections()) == list(range(1, 8))


def test_every_cited_section_exists():
    cited = cited_sections()
    assert len(cited) >= 5  # the pattern does find the citations
    missing = {n: files for n, files in cited.items() if n not in page_sections()}
    assert not missing, missing


def test_every_named_test_is_defined():
    ids, missing = undefined_tests(PAGE)
    assert len(ids) >= 40
    assert not missing, missing


def test_the_page_is_in_the_toctree():
    toctree = (ROOT / "docs" / "index.md").read_text().split("```{toctree}")[1].split("```")[0]
    assert "conventions" in toctree.split()
