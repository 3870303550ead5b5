"""The "The paper's results" page (docs/paper-results.md) matches the commands and the paper."""

import re
from pathlib import Path

from qsa.commands.reproduce import REPRODUCTIONS
from qsa.paper import CONVERGENCE
from tests.helpers import undefined_tests

DOCS = Path(__file__).resolve().parent.parent / "docs"
PAGE = DOCS / "paper-results.md"


def rows(text):
    """The cells of every Markdown table row of the page."""
    return [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in text.splitlines() if line.startswith("|") and "---" not in line]


def test_every_reproduce_subcommand_has_one_row():
    listed = [m.group(1) for r in rows(PAGE.read_text())
              if (m := re.fullmatch(r"`qsa reproduce (\w+)`", r[0]))]
    assert sorted(listed) == sorted(REPRODUCTIONS)


def test_the_paper_columns_are_the_papers_numbers():
    table = {int(r[0]): float(r[1]) for r in rows(PAGE.read_text()) if r[0].isdigit()}
    assert table == CONVERGENCE.paper_differences
    steps = {}
    for r in rows(PAGE.read_text()):
        m = re.fullmatch(r"\$10\^\{(-\d)\}\$", r[0])
        if m:
            steps[float(f"1e{m.group(1)}")] = int(r[1])
    assert steps == CONVERGENCE.paper_steps


def test_named_tests_and_figures_exist():
    ids, missing = undefined_tests(PAGE)
    assert ids and not missing, missing
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", PAGE.read_text())
    assert figures and all((DOCS / f).is_file() for f in figures)


def test_the_page_is_in_the_toctree():
    toctree = (DOCS / "index.md").read_text().split("```{toctree}")[1].split("```")[0]
    assert "paper-results" in toctree.split()
