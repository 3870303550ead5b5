"""One spelling per option across subcommands, and ``--help`` defaults that are true."""

import argparse
import re

import pytest

from qsa.cli import build_parser


def leaf_parsers(parser, prefix="qsa"):
    """``{"qsa flow cha": parser, ...}`` for every parser that runs a command."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return {prefix: parser}
    out = {}
    for name, sub in subs[0].choices.items():
        out.update(leaf_parsers(sub, f"{prefix} {name}"))
    return out


LEAVES = leaf_parsers(build_parser())


def options(parser):
    return [a for a in parser._actions if a.option_strings and a.dest != "help"]


def stated_default(parser, action):
    """The text after "(default" in the expanded help, up to ")" or ";", or None."""
    text = parser._get_formatter()._expand_help(action) if action.help else ""
    m = re.search(r"\(default:? ([^);]*)", text)
    return None if m is None else m.group(1)


def shown(value):
    if isinstance(value, (list, tuple)):
        return " ".join(shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def test_every_stated_default_is_the_default():
    checked = 0
    for prog, parser in LEAVES.items():
        for action in options(parser):
            stated = stated_default(parser, action)
            default = action.default
            if stated is None or default in (None, False, argparse.SUPPRESS):
                continue
            where = (prog, action.option_strings, stated, default)
            if isinstance(default, (int, float)) and not isinstance(default, bool):
                assert float(stated.split()[0].rstrip(":,")) == float(default), where
            elif isinstance(default, (list, tuple)):
                assert stated.startswith(shown(default)), where
            else:
                assert shown(default) in stated, where
            checked += 1
    assert checked >= 20


def test_defaults_resolved_later_are_stated_from_their_source():
    from qsa.paper.scenarios import CHAScenario, ConvergenceScenario, FacetScenario

    def help_of(prog, flag):
        parser = LEAVES[prog]
        action = next(a for a in options(parser) if flag in a.option_strings)
        return parser._get_formatter()._expand_help(action)

    assert f"default {FacetScenario().t_final:g}" in help_of("qsa reproduce facet", "--t-final")
    assert "the paper's figure stops at t = 2" in help_of("qsa reproduce facet", "--t-final")
    assert f"default {CHAScenario().t_final:g}" in help_of("qsa reproduce snowflake",
                                                          "--t-final")
    assert f"default {CHAScenario().N}" in help_of("qsa reproduce folding", "--N")
    sc = ConvergenceScenario()
    assert " ".join(map(str, sc.Ns)) in help_of("qsa reproduce convergence", "--Ns")
    assert f"default {sc.N_steps}" in help_of("qsa reproduce timesteps", "--N")
    assert f"default {sc.t_final:g}" in help_of("qsa reproduce timesteps", "--t-final")


def test_one_spelling_per_concept():
    primary = {}
    for parser in LEAVES.values():
        for action in options(parser):
            primary.setdefault(action.dest, set()).add(action.option_strings[0])
    several = {dest: flags for dest, flags in primary.items() if len(flags) > 1}
    assert not several, several
    lowered = {}
    for flags in primary.values():
        (flag,) = flags
        lowered.setdefault(flag.lower(), set()).add(flag)
    assert all(len(v) == 1 for v in lowered.values()), lowered  # no --l-star vs --L-star


@pytest.mark.parametrize("argv, dest, value", [
    (["flow", "cha", "--l-star", "0.3"], "l_star", 0.3),
    (["flow", "cha", "--kernel-length", "0.3"], "l_star", 0.3),
    (["flow", "facet", "--L-star", "6"], "L_star", 6.0),
    (["flow", "facet", "--preferred-length", "6"], "L_star", 6.0),
    (["reproduce", "snowflake", "--l-star", "0.1"], "l_star", 0.1),
    (["flow", "cha", "--no-progress"], "progress", False),
    (["reproduce", "facet", "--no-progress"], "progress", False),
])
def test_old_spellings_are_kept_as_aliases(argv, dest, value):
    assert getattr(build_parser().parse_args(argv), dest) == value
