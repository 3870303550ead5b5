"""Regenerate docs/performance.md: run the benchmarks and put their tables on the page.

Each benchmark of this directory runs as ``python benchmarks/<name>.py [args]`` in a
fresh interpreter with one BLAS thread; its printed tables go on the page verbatim,
with the command, the wall time of the whole script and the machine. Sections are
delimited by ``<!-- bench: <name> -->`` markers, so ``--only NAME ...`` reruns a few
benchmarks and keeps the other sections of the existing page as they are.

Usage::

    python benchmarks/make_performance_page.py            # all, --quick where there is one
    python benchmarks/make_performance_page.py --full     # the full sweeps (hours)
    python benchmarks/make_performance_page.py --only bench_spectra bench_polish
    python benchmarks/make_performance_page.py --list     # the benchmarks and their arguments
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy
import scipy

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "performance.md"


@dataclass(frozen=True)
class Bench:
    """One benchmark script: its arguments on the page (quick) and for ``--full``."""

    name: str
    title: str
    quick: tuple[str, ...] = ()
    full: tuple[str, ...] = ()


BENCHES = (
    Bench("bench_foundation", "Foundation operators against N", ("--quick",)),
    Bench("bench_equilibria", "Semi-analytic N-pulse equilibria"),
    Bench("bench_polish", "Newton polish"),
    Bench("bench_spectra", "Slow eigenvalues at every resolution"),
    Bench("bench_second_order", "Second-order energies", ("--quick",)),
    Bench("bench_dae_models", "DAE residual and Newton matrix against N", ("--quick",)),
    Bench("bench_flow", "The curve flow", ("--quick",)),
    Bench("bench_adhesion_hessian", "The adhesion Hessian", ("--quick",)),
    Bench("bench_folded", "Spectra of folded (CHA) states", ("--quick",)),
    Bench("bench_far_field", "Hierarchical adhesion pair Hessian", ("--quick",), ("--large",)),
    Bench("bench_pair_interp", "Interpolated adhesion pair Hessian"),
    Bench("bench_capacitance_gmres", "The capacitance by deflated GMRES",
          ("--N", "1200", "2400", "--compare")),
    Bench("bench_constraints", "Length and area constraints"),
    Bench("bench_bifurcation", "Bifurcation diagrams"),
    Bench("bench_reduction", "The front ODE against the DAE", ("1200",), ("1200", "2400")),
    Bench("bench_coarsening", "Coarsening by the front ODE"),
    Bench("bench_sweep", "Parameter sweeps on each executor"),
    Bench("bench_memory", "Peak memory of the command line", ("--quick",)),
    Bench("bench_paper_runs", "The paper's full-scale simulations", ("--quick",), ("--cha",)),
)
HEADER = """# Performance

The tables below are printed by the scripts of `benchmarks/` in the repository and
put on this page by `python benchmarks/make_performance_page.py` (the fast settings:
`--quick` where a script has one; `--full` runs the complete sweeps). Each section
names the command, the wall time of the whole script and the date it ran. Times are
those of the machine named below, one BLAS thread per process; a table's fitted
exponent is its cost's growth with N. To measure on your machine, run the same
command.
"""


def section(bench, argv, output, seconds, when):
    """The page's section of one benchmark run, between its markers."""
    cmd = " ".join(["python", f"benchmarks/{bench.name}.py", *argv])
    body = output.rstrip() or "(no output)"
    return (f"<!-- bench: {bench.name} -->\n## {bench.title}\n\n`{cmd}` — {seconds:.0f} s, "
            f"{when}\n\n```text\n{body}\n```\n<!-- end: {bench.name} -->\n")


def machine():
    """One line naming the machine, Python and the numerical libraries."""
    cpus = os.cpu_count()
    return (f"{platform.machine()} · {cpus} cores · Python {platform.python_version()} · "
            f"NumPy {numpy.__version__} · SciPy {scipy.__version__}")


def existing_sections(text):
    """``{name: section text}`` of a page made by this script."""
    pattern = r"(<!-- bench: (\S+) -->\n.*?<!-- end: \2 -->\n)"
    return {m.group(2): m.group(1) for m in re.finditer(pattern, text, re.S)}


def render(sections, machine_line):
    """The whole page from the sections, in the order of ``BENCHES``."""
    parts = [HEADER, f"\nMachine: {machine_line}.\n"]
    for b in BENCHES:
        if b.name in sections:
            parts.append("\n" + sections[b.name])
    return "".join(parts)


def run(bench, argv, timeout):
    """Run one benchmark; ``(output, seconds)``, the output saying so if it failed."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get(
        "PYTHONPATH", "").split(os.pathsep) if p])
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, str(ROOT / "benchmarks" / f"{bench.name}.py"),
                            *argv], capture_output=True, text=True, env=env,
                           timeout=timeout, cwd=ROOT)
        out = p.stdout
        if p.returncode != 0:
            tail = "\n".join(p.stderr.strip().splitlines()[-5:])
            out += f"\n[the script failed, exit code {p.returncode}]\n{tail}"
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        out += f"\n[stopped after {timeout:.0f} s]"
    return out, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", action="store_true", help="the complete sweeps (hours)")
    ap.add_argument("--only", nargs="+", metavar="NAME", default=None,
                    help="rerun these benchmarks, keep the other sections of the page")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and stop")
    ap.add_argument("--timeout", type=float, default=1800.0,
                    help="seconds allowed per script (default 1800)")
    ap.add_argument("--page", type=Path, default=PAGE, help="the page to write")
    args = ap.parse_args(argv)
    names = {b.name for b in BENCHES}
    if args.list:
        for b in BENCHES:
            print(f"{b.name:<24} quick: {' '.join(b.quick) or '-':<10} "
                  f"full: {' '.join(b.full) or '-'}")
        return 0
    if args.only:
        unknown = sorted(set(args.only) - names)
        if unknown:
            ap.error(f"--only: unknown benchmark {', '.join(unknown)}; "
                     f"choose from {', '.join(sorted(names))}")
    sections = existing_sections(args.page.read_text()) if args.page.exists() else {}
    chosen = [b for b in BENCHES if args.only is None or b.name in args.only]
    for b in chosen:
        argv_b = b.full if args.full else b.quick
        print(f"running {b.name} {' '.join(argv_b)} ...", flush=True)
        out, sec = run(b, argv_b, args.timeout)
        when = datetime.now(timezone.utc).strftime("%Y-%m-%d")
        sections[b.name] = section(b, argv_b, out, sec, when)
        args.page.write_text(render(sections, machine()))  # each finished table lands
        print(f"  {sec:.0f} s", flush=True)
    print(f"wrote {args.page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
