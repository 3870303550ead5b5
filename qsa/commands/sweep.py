"""``qsa sweep STUDY --param NAME=SPEC ... --out DIR``: a parameter study, resumable.

Examples
--------
``qsa sweep npulse --param alpha=0.05:0.3:11 --param n_pulses=2,3 --out np-sweep``
``qsa sweep spectrum --param alpha=0.05:0.15:5 --out sp --dask-local 2 --json``
``qsa sweep spectrum --param alpha=0.1,0.2 --out sp --dask tcp://scheduler:8786``

Points already stored in ``DIR/points`` are reused (an interrupted sweep resumes);
the table is ``DIR/results.csv``.
"""

from __future__ import annotations

import contextlib
import json
import socket

from qsa.commands._options import int_at_least

#: Column plotted by ``--plot`` when ``--y`` is not given.
DEFAULT_Y = {"npulse": "residual", "spectrum": "lambda_0", "circle-spectrum": "max_rel_error",
             "splice-spectrum": "slow_0", "flow-rate": "rate"}


def _first_numeric(res, params):
    for c in res.columns:
        if c not in params and c not in ("success", "message") and \
                any(isinstance(r.get(c), float) for r in res.rows):
            return c
    raise ValueError("--plot: the table has no numeric result column; pass --y")


def add_parser(sub):
    from qsa.studies import STUDIES

    p = sub.add_parser("sweep", help="map a study over a parameter grid (resumable, Dask)",
                       description=__doc__.split("\n\n")[0])
    p.add_argument("study", choices=sorted(STUDIES), help="the study at each point")
    p.add_argument("--param", action="append", default=[], metavar="NAME=SPEC",
                   help="grid axis: NAME=start:stop:num (linspace) or NAME=v1,v2,... "
                        "(repeat for a product grid); other parameters keep their defaults")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--workers", type=int_at_least(1), default=None,
                   help="local process pool size (default: CPU count; 1 = in-process)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--dask", metavar="ADDRESS", help="run on the Dask scheduler at ADDRESS")
    g.add_argument("--dask-local", type=int_at_least(1), metavar="N",
                   help="run on a local Dask cluster of N worker processes")
    p.add_argument("--on-corrupt", choices=["recompute", "raise"], default="recompute",
                   help="a stored point that cannot be read: recompute it (default) or stop")
    p.add_argument("--json", action="store_true", help="JSON summary on stdout")
    p.add_argument("--plot", metavar="FILE", help="plot --y against --x to FILE")
    p.add_argument("--x", default=None, help="x column of --plot (default: the first param)")
    p.add_argument("--y", default=None,
                   help="y column of --plot (default by study: residual, lambda_0, ...)")
    p.add_argument("--progress", action=argparse_bool(), default=None,
                   help="progress bar (default: on a terminal)")
    p.set_defaults(func=run, interrupt_hint=lambda args: f"the points finished are kept in "
                   f"{args.out}/points; the same command computes the others")
    return p


def check_scheduler(address, timeout=5.0):
    """Refuse at once a ``--dask`` address where no Dask scheduler answers.

    ``tcp://host:port``, ``tls://host:port`` and ``host:port`` are probed: a TCP
    connection must open and the scheduler's handshake (which it sends as soon as
    a connection opens) arrive within ``timeout`` seconds. Other schemes are left
    to Dask.

    Raises
    ------
    ValueError
        Nothing listens there, nothing answers, or the address does not parse.
    """
    rest = address
    for scheme in ("tcp://", "tls://"):
        if rest.startswith(scheme):
            rest = rest[len(scheme):]
            break
    else:
        if "://" in rest:
            return
    host, sep, port = rest.rpartition(":")
    if not sep or not port.isdigit():
        raise ValueError(f"--dask {address}: expected tcp://HOST:PORT (e.g. "
                         "tcp://127.0.0.1:8786)")
    try:
        with socket.create_connection((host.strip("[]") or "127.0.0.1", int(port)),
                                      timeout=timeout) as conn:
            conn.settimeout(timeout)
            answered = bool(conn.recv(1))
        reason = "it closed the connection without a handshake"
    except TimeoutError:
        answered, reason = False, f"no answer within {timeout:g} s"
    except OSError as exc:
        answered, reason = False, exc.strerror or str(exc)
    if not answered:
        raise ValueError(f"--dask {address}: no Dask scheduler there ({reason}); start one "
                         "with `dask scheduler`, or use --dask-local N")


def argparse_bool():
    import argparse

    return argparse.BooleanOptionalAction


def run(args):
    from qsa.studies import STUDIES
    from qsa.sweep import ParameterGrid, dask_executor, run_sweep

    if not args.param:
        raise ValueError("--param: give at least one NAME=SPEC")
    grid = ParameterGrid.parse(args.param)
    study = STUDIES[args.study]
    if args.dask is not None:
        check_scheduler(args.dask)
        ctx = dask_executor(address=args.dask)
    elif args.dask_local is not None:
        ctx = dask_executor(n_workers=args.dask_local)
    else:
        ctx = contextlib.nullcontext(None)
    with contextlib.ExitStack() as stack:
        try:
            executor = stack.enter_context(ctx)
        except (OSError, TimeoutError) as exc:
            where = args.dask or f"a local cluster of {args.dask_local} workers"
            raise ValueError(f"--dask: cannot use {where} ({exc})") from None
        res = run_sweep(study, grid, args.out, executor=executor, workers=args.workers,
                        progress=args.progress, on_corrupt=args.on_corrupt)
    summary = res.summary()
    if args.plot:
        from qsa import plotting

        x = args.x or grid.names[0]
        y = args.y or DEFAULT_Y.get(args.study) or _first_numeric(res, grid.names)
        plotting.save(plotting.plot_sweep(res, x, y, title=f"qsa sweep {args.study}"),
                      args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"qsa sweep {args.study}: {res.message} in {res.seconds:.2f} s")
        print(f"  table: {res.table_path}")
        for r in res.rows:
            if not r["success"]:
                point = ", ".join(f"{k}={r[k]}" for k in grid.names)
                print(f"  failed at {point}: {r['message']}")
        if args.plot:
            print(f"  figure written to {args.plot}")
    return 0 if res.success else 1
