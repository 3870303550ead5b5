"""The site's Notebooks page and examples gallery cover what the repository holds.

The notebooks of ``notebooks/`` are the single source of the site's notebook pages
(the build copies and executes them); the gallery is made of ``examples/exNN_*.py``.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = (ROOT / "docs" / "notebooks.md").read_text()
CONF = (ROOT / "docs" / "conf.py").read_text()
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
EXAMPLES = sorted((ROOT / "examples").glob("ex[0-9][0-9]_*.py"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_every_notebook_has_a_row(path):
    assert f"(notebooks/{path.name})" in PAGE, f"docs/notebooks.md does not describe {path.name}"


def test_every_row_is_a_notebook():
    linked = set(re.findall(r"\(notebooks/([^)]+\.ipynb)\)", PAGE))
    assert linked == {p.name for p in NOTEBOOKS}


def test_the_build_executes_and_fails_on_errors():
    assert re.search(r'^nb_execution_mode = "(cache|force)"', CONF, re.M)
    assert re.search(r"^nb_execution_raise_on_error = True", CONF, re.M)


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_is_a_gallery_entry(path):
    text = path.read_text()
    # sphinx-gallery needs a docstring whose first line is the title, underlined by =
    m = re.match(r'"""(.+)\n(=+)\n', text)
    assert m, f"{path.name}: the docstring must open with a title underlined by '='"
    assert len(m.group(2)) >= len(m.group(1)), f"{path.name}: title underline too short"
    assert 'if __name__ == "__main__":' in text


def test_the_pages_are_in_the_toctree():
    index = (ROOT / "docs" / "index.md").read_text()
    assert "\nnotebooks\n" in index and "\ngallery/index\n" in index
