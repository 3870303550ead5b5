"""docs/performance.md is made by benchmarks/make_performance_page.py from every benchmark."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = importlib.util.spec_from_file_location(
    "make_performance_page", ROOT / "benchmarks" / "make_performance_page.py")
page = importlib.util.module_from_spec(SPEC)
sys.modules[SPEC.name] = page  # the module's dataclass looks itself up there
SPEC.loader.exec_module(page)


def test_every_benchmark_is_on_the_page_list():
    scripts = {p.stem for p in (ROOT / "benchmarks").glob("bench_*.py")}
    assert scripts == {b.name for b in page.BENCHES}


def test_the_committed_page_has_every_section():
    sections = page.existing_sections(page.PAGE.read_text())
    assert set(sections) == {b.name for b in page.BENCHES}
    for name, text in sections.items():
        assert "[the script failed" not in text, f"{name} failed when the page was made"
        assert "[stopped after" not in text, f"{name} timed out when the page was made"


def test_sections_round_trip_and_keep_their_order():
    b1, b2 = page.BENCHES[0], page.BENCHES[1]
    s = {b2.name: page.section(b2, ("--quick",), "table 2\n", 2.0, "2026-01-02"),
         b1.name: page.section(b1, (), "N  time\n10  1.0\n", 1.0, "2026-01-01")}
    text = page.render(s, "test machine")
    assert page.existing_sections(text) == s
    assert text.index(b1.title) < text.index(b2.title)
    assert f"`python benchmarks/{b2.name}.py --quick` — 2 s" in text
    # --only keeps the other sections: re-rendering one changed section changes only it
    s2 = dict(s, **{b2.name: page.section(b2, (), "new\n", 3.0, "2026-01-03")})
    again = page.existing_sections(page.render(s2, "test machine"))
    assert again[b1.name] == s[b1.name] and "new" in again[b2.name]


def test_the_page_is_in_the_toctree():
    assert "\nperformance\n" in (ROOT / "docs" / "index.md").read_text()


def test_only_rejects_unknown_names(capsys):
    try:
        page.main(["--only", "bench_nothing", "--page", "/nonexistent/page.md"])
    except SystemExit as e:
        assert e.code == 2
    err = capsys.readouterr().err
    assert "--only: unknown benchmark bench_nothing" in err
