"""``qsa flow cha|facet``: run a DAE curve flow and write its data and figures.

Examples
--------
``qsa flow cha --N 100 --t-final 0.2 --tol 1e-4 --out run-cha``  (the appendix example)
``qsa flow facet --alpha 0.1 --kstar 5 --beta 5 --L-star 8 --shape wobbly --lobes 9 --N 600``
``qsa flow cha --resume run-cha/checkpoint.npz --t-final 0.4``
``qsa flow facet --shape wobbly --lobes 7 --N 200 --t-final 0.02 --movie facet.gif``
"""

from __future__ import annotations

import json
import os

import numpy as np


def add_parser(sub):
    p = sub.add_parser("flow", help="run a curve flow (CHA or faceting): data + figures",
                       description=__doc__.split("\n\n")[0])
    models = p.add_subparsers(dest="model", metavar="MODEL", required=True)
    q = models.add_parser("cha", help="Canham-Helfrich + length penalty + adhesion")
    q.add_argument("--eps", type=float, default=0.1, help="bending rigidity (default 0.1)")
    q.add_argument("--beta", type=float, default=1.0, help="length penalty (default 1)")
    q.add_argument("--rho", type=float, default=1.5, help="precompression (default 1.5)")
    q.add_argument("--A0", type=float, default=10.0, help="adhesion strength; 0 = off (10)")
    q.add_argument("--l-star", type=float, default=0.5, help="kernel width (default 0.5)")
    q.add_argument("--a", type=float, default=1.0, help="kernel shape (default 1)")
    _common(q, t_final=0.2)
    q = models.add_parser("facet", help="the faceting flow (e:Facet-NV)")
    q.add_argument("--alpha", type=float, default=0.1, help="front width (default 0.1)")
    q.add_argument("--kstar", type=float, default=5.0, help="second well (default 5)")
    q.add_argument("--beta", type=float, default=5.0, help="length penalty (default 5)")
    q.add_argument("--L-star", type=float, default=None,
                   help="preferred length (default: 1.2 x the initial length)")
    _common(q, t_final=1e-3)
    return p


def _common(q, t_final):
    q.add_argument("--shape", choices=["paper", "wobbly", "circle"], default="paper",
                   help="initial curve: the appendix trillium r = 1 + 0.35 cos 3t (+0.05 sin 4t "
                        "in x), a wobbly circle r = R(1 + amp cos(lobes t)), or a circle")
    q.add_argument("--radius", type=float, default=1.0, help="R of wobbly/circle (default 1)")
    q.add_argument("--amp", type=float, default=0.05, help="wobble amplitude (default 0.05)")
    q.add_argument("--lobes", type=int, default=5, help="wobble lobes (default 5)")
    q.add_argument("--init", metavar="FILE",
                   help="initial curve from a text file of x y rows (overrides --shape)")
    q.add_argument("--N", type=int, default=100, help="nodes (default 100)")
    q.add_argument("--t-final", type=float, default=t_final, help=f"final time ({t_final:g})")
    q.add_argument("--tol", type=float, default=1e-4, help="local error tolerance (1e-4)")
    q.add_argument("--method", choices=["be", "bdf2"], default="be",
                   help="backward Euler with step doubling (paper) or BDF2")
    q.add_argument("--snapshots", type=int, default=None,
                   help="snapshots saved (default 6; 60 with --movie)")
    q.add_argument("--out", default=None, help="folder for result.npz, summary.json, flow.png")
    q.add_argument("--checkpoint", default=None,
                   help="checkpoint file (default OUT/checkpoint.npz when --out is given)")
    q.add_argument("--resume", default=None, metavar="CHECKPOINT", help="continue a run")
    q.add_argument("--no-progress", action="store_true", help="no progress bar")
    q.add_argument("--json", action="store_true", help="JSON summary on stdout")
    q.add_argument("--plot", metavar="FILE", help="write the figure to FILE")
    q.add_argument("--movie", metavar="FILE",
                   help="write an animation of the snapshots to FILE.gif (Pillow) or "
                        "FILE.mp4 (needs ffmpeg)")
    q.add_argument("--fps", type=float, default=10.0, help="movie frames per second (10)")
    q.set_defaults(func=run)


def initial_curve(args, M=4000):
    """Samples of the requested initial curve (closed, counter-clockwise)."""
    if args.init:
        data = np.loadtxt(args.init, ndmin=2)
        if data.shape[1] != 2:
            raise ValueError(f"--init {args.init}: expected two columns x y")
        return data[:, 0], data[:, 1]
    th = 2 * np.pi * np.arange(M) / M
    if args.shape == "paper":
        r = 1 + 0.35 * np.cos(3 * th)
        return r * np.cos(th) + 0.05 * np.sin(4 * th), r * np.sin(th)
    r = args.radius * (1 + (args.amp * np.cos(args.lobes * th) if args.shape == "wobbly" else 0))
    return r * np.cos(th), r * np.sin(th)


def build_model(args, xy):
    from qsa.flows import CHA, FacetingFlow

    if args.model == "cha":
        return CHA(eps=args.eps, beta=args.beta, rho=args.rho, A0=args.A0, l_star=args.l_star,
                   a=args.a)
    L_star = args.L_star
    if L_star is None:
        x, y = xy
        L_star = 1.2 * float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))
    return FacetingFlow(alpha=args.alpha, kstar=args.kstar, beta=args.beta, L_star=L_star)


def summarize(res):
    return {
        "success": bool(res.success), "status": int(res.status), "message": res.message,
        "method": res.method, "tol": res.tol, "N": res.N, "t_final": float(res.t[-1]),
        "n_steps": res.n_steps, "n_rejected": res.n_rejected, "n_newton": res.n_newton,
        "n_lu": res.n_lu, "energy_initial": float(res.energy_steps[0]),
        "energy_final": float(res.energy_steps[-1]), "length_final": float(res.length_steps[-1]),
        "checkpoint": res.checkpoint, "model": res.system.metadata(),
    }


def run(args):
    from qsa.flows import solve_flow

    if args.movie:  # refuse a movie that cannot be written before running the flow
        from qsa.plotting import movie_writer

        movie_writer(args.movie)
        if not args.fps > 0:
            raise ValueError(f"--fps must be positive, got {args.fps:g}")
    snapshots = args.snapshots if args.snapshots is not None else (60 if args.movie else 6)
    if snapshots < 2:
        raise ValueError(f"--snapshots must be at least 2, got {snapshots}")
    xy = initial_curve(args)
    model = build_model(args, xy)
    checkpoint = args.checkpoint
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        if checkpoint is None:
            checkpoint = os.path.join(args.out, "checkpoint.npz")
    t_eval = np.linspace(0.0, args.t_final, snapshots)
    res = solve_flow(model, None if args.resume else xy, args.t_final, N=args.N, tol=args.tol,
                     method=args.method, t_eval=t_eval, checkpoint=checkpoint,
                     resume=args.resume, progress=False if args.no_progress else None)
    summary = summarize(res)
    if args.out:
        from qsa.io import save_npz

        save_npz(os.path.join(args.out, "result.npz"),
                 {"t": res.t, "states": res.states, "energy": res.energy,
                  "length": res.length, "t_steps": res.t_steps,
                  "energy_steps": res.energy_steps, "length_steps": res.length_steps},
                 summary)
        with open(os.path.join(args.out, "summary.json"), "w") as fh:
            json.dump(summary, fh, indent=2)
    figure = args.plot or (os.path.join(args.out, "flow.png") if args.out else None)
    if figure:
        from qsa.plotting import plot_flow, save

        save(plot_flow(res, title=f"{res.system.metadata()['model']}, N = {res.N}"), figure)
        summary["figure"] = figure
    if args.movie:
        from qsa.plotting import animate_flow

        animate_flow(res, args.movie, fps=args.fps)
        summary["movie"] = args.movie
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{summary['model']['model']} N={res.N} {res.method} tol={res.tol:g}: "
              f"{res.message} t={summary['t_final']:.6g}, {res.n_steps} steps "
              f"({res.n_rejected} rejected), {res.n_newton} Newton iterations, "
              f"{res.n_lu} factorizations; energy {summary['energy_initial']:.6g}"
              f" -> {summary['energy_final']:.6g}")
        if args.out:
            print(f"data and figure written to {args.out}/")
        if args.movie:
            print(f"movie ({len(res.t)} frames) written to {args.movie}")
    return 0 if res.success else 1
