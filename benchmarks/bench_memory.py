"""Peak memory of the command line's runs against the estimates that guard them.

Each row runs ``qsa ...`` in a fresh interpreter, reads its peak resident set size
(``getrusage(RUSAGE_SELF).ru_maxrss``) and prints it next to the estimate of
:mod:`qsa.commands._memory` (the fit times its margin), so the fit can be checked
or refitted on another machine: a ratio estimate/measured below 1 means the
guard would let a run through that needs more than it says.

Usage::

    python benchmarks/bench_memory.py            # the moderate-N table (a few minutes)
    python benchmarks/bench_memory.py --quick    # the smallest row of each kind
    python benchmarks/bench_memory.py --fit      # also least-squares fits per kind

Timings and memory are per run; other processes on the machine do not change the
RSS of a run, only its wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)  # the qsa of this checkout, as in the measured subprocesses

#: kind -> (command line with {N}, sizes); the kind is a key of FOOTPRINTS
RUNS = {
    "flow-facet": ("flow facet --N {N} --t-final 2e-5 --tol 1e-3 --no-progress",
                   [8000, 32000, 128000]),
    "flow-cha": ("flow cha --N {N} --t-final 2e-5 --tol 1e-3 --no-progress", [1000, 2000]),
    "flow-cha l*=0.05": ("flow cha --kernel-length 0.05 --N {N} --t-final 2e-5 --tol 1e-3 "
                         "--no-progress", [2000, 8000]),
    "equilibrium-fourier": ("equilibrium npulse --pulses 3 --alpha 0.1 --N {N}",
                            [1001, 2001, 4001]),
    "equilibrium-fd": ("equilibrium npulse --pulses 3 --alpha 0.1 --fd --N {N}",
                       [16000, 64000, 256000]),
    "polish-fourier": ("equilibrium npulse --pulses 3 --alpha 0.1 --polish --N {N}",
                       [501, 1001, 2001]),
    "polish-fd": ("equilibrium npulse --pulses 3 --alpha 0.1 --fd --polish --N {N}",
                  [4000, 16000, 64000]),
    "spectrum-fourier": ("spectrum npulse --pulses 3 --alpha 0.1 --N {N}", [401, 801, 1201]),
    "spectrum-fourier-noreject": ("spectrum npulse --pulses 3 --alpha 0.1 --no-reject "
                                  "--N {N}", [401, 801]),
    "spectrum-fd": ("spectrum npulse --pulses 3 --alpha 0.1 --fd --N {N}", [1600, 3200]),
    "spectrum-k-fourier": ("spectrum npulse --pulses 3 --alpha 0.1 --k 6 --sigma 0 --N {N}",
                           [801, 2001]),
    "spectrum-k-fd": ("spectrum npulse --pulses 3 --alpha 0.1 --fd --k 6 --sigma 0 --N {N}",
                      [8000, 32000]),
}

WRAPPER = """
import json, resource, sys
from qsa.cli import main
code = main(sys.argv[1:])
print(json.dumps({"code": code, "maxrss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}),
      file=sys.stderr)
"""


def measure(argv):
    env = dict(os.environ, PYTHONPATH=ROOT, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg",
               QSA_MEMORY_LIMIT="1T")
    proc = subprocess.run([sys.executable, "-c", WRAPPER, *argv], env=env,
                          capture_output=True, text=True)
    last = proc.stderr.strip().splitlines()[-1]
    data = json.loads(last)
    return data["code"], data["maxrss"] * 1024  # Linux reports kB


def estimate(kind, argv, N):
    from qsa.commands import _memory as m

    if kind.startswith("flow"):
        from qsa.cli import build_parser
        from qsa.commands.flow import build_model, initial_curve

        args = build_parser().parse_args(argv)
        xy, eq = initial_curve(args)
        return m.flow_bytes(build_model(args, xy, eq), xy, N)[0]
    fourier = "--fd" not in argv
    if kind.startswith("equilibrium"):
        return m.equilibrium_bytes(N, fourier)[0]
    if kind.startswith("polish"):
        return m.polish_bytes(N, fourier)[0]
    k = 6 if "--k" in argv else None
    return m.spectrum_bytes(N, fourier, k=k, reject="--no-reject" not in argv)[0]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="the smallest size of each kind")
    p.add_argument("--fit", action="store_true", help="print base + a N + c N^2 fits")
    p.add_argument("--only", nargs="*", default=None, help="kinds to run")
    args = p.parse_args()
    from qsa.commands._memory import format_bytes

    print(f"{'kind':28s} {'N':>7s} {'measured':>10s} {'estimate':>10s} {'ratio':>6s}")
    for kind, (line, sizes) in RUNS.items():
        if args.only and kind not in args.only:
            continue
        rows = []
        for N in sizes[:1] if args.quick else sizes:
            argv = line.format(N=N).split()
            code, rss = measure(argv)
            est = estimate(kind, argv, N)
            rows.append((N, rss))
            print(f"{kind:28s} {N:>7d} {format_bytes(rss):>10s} {format_bytes(est):>10s} "
                  f"{est / rss:>6.2f}" + ("" if code in (0, 1) else f"  (exit {code})"),
                  flush=True)
        if args.fit and len(rows) >= 2:
            N = np.array([r[0] for r in rows], float)
            R = np.array([r[1] for r in rows], float)
            A = np.column_stack([np.ones_like(N), N, N**2])[:, : min(3, len(rows))]
            coef = np.linalg.lstsq(A, R, rcond=None)[0]
            print(f"{'':28s} fit: base {coef[0] / 2**20:.0f} MiB, per node {coef[1]:.3g} B"
                  + (f", per node^2 {coef[2]:.3g} B" if coef.size > 2 else ""))


if __name__ == "__main__":
    main()
