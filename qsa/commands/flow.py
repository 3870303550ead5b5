"""``qsa flow cha|facet|fch``: run a DAE curve flow and write its data and figures.

Examples
--------
``qsa flow cha --N 100 --t-final 0.2 --tol 1e-4 --out run-cha``  (the appendix example)
``qsa flow facet --alpha 0.1 --kstar 5 --beta 5 --preferred-length 8 --shape wobbly --lobes 9``
``qsa flow cha --resume run-cha/checkpoint.npz --t-final 0.4``
``qsa flow cha --resume --out run-cha --t-final 0.4``  (the same: the checkpoint in --out)
``qsa flow facet --init eq.npz --t-final 0.01``  (from ``qsa equilibrium ... --save eq.npz``)
``qsa flow facet --shape wobbly --lobes 7 --N 200 --t-final 0.02 --movie facet.gif``
``qsa flow fch --alpha 0.2 --eta 0.5 --kstar 1 --t-final 0.5``  (a second-order energy)

A resumed run takes its model, grid, method and tolerance from the checkpoint:
options that contradict it are refused, options about the initial curve are
ignored with a warning.
"""

from __future__ import annotations

import json
import os

import numpy as np

from qsa.commands._errors import note, warn
from qsa.commands._options import (
    finite_float,
    int_at_least,
    nonnegative_float,
    positive_float,
)

#: Model options of each subcommand (dest -> default) and the model field they set.
MODEL_DEFAULTS = {
    "cha": {"eps": 0.1, "beta": 1.0, "rho": 1.5, "A0": 10.0, "l_star": 0.5, "a": 1.0},
    "facet": {"alpha": 0.1, "kstar": 5.0, "beta": 5.0, "L_star": None},
    "fch": {"alpha": 0.2, "eta": 0.5, "kstar": 1.0, "beta": 1.0, "L_star": None},
}
#: Run options (dest -> default) shared by both models; ``t_final`` by model.
RUN_DEFAULTS = {"N": 100, "tol": 1e-4, "method": "be"}
T_FINAL = {"cha": 0.2, "facet": 1e-3, "fch": 0.5}
#: Options about the initial curve (ignored, with a warning, by ``--resume``).
INITIAL_OPTIONS = ("init", "shape", "radius", "amp", "lobes")
INITIAL_DEFAULTS = {"shape": "paper", "radius": 1.0, "amp": 0.05, "lobes": 5}
_MODEL_NAMES = {"cha": "CHA", "facet": "FacetingFlow", "fch": "SecondOrderFlow"}


def add_parser(sub):
    p = sub.add_parser("flow", help="run a curve flow (CHA or faceting): data + figures",
                       description=__doc__.split("\n\n")[0])
    models = p.add_subparsers(dest="model", metavar="MODEL", required=True)
    d = MODEL_DEFAULTS["cha"]
    q = models.add_parser("cha", help="Canham-Helfrich + length penalty + adhesion")
    q.add_argument("--eps", type=positive_float, help=f"bending rigidity (default {d['eps']:g})")
    q.add_argument("--beta", type=nonnegative_float,
                   help=f"length penalty (default {d['beta']:g})")
    q.add_argument("--rho", type=positive_float, help=f"precompression (default {d['rho']:g})")
    q.add_argument("--A0", type=nonnegative_float,
                   help=f"adhesion strength; 0 = off (default {d['A0']:g})")
    q.add_argument("--kernel-length", "--l-star", dest="l_star", metavar="LENGTH",
                   type=positive_float, help=f"adhesion kernel length l* (default {d['l_star']:g})")
    q.add_argument("--a", type=positive_float, help=f"kernel shape (default {d['a']:g})")
    _common(q, "cha")
    d = MODEL_DEFAULTS["facet"]
    q = models.add_parser("facet", help="the faceting flow (e:Facet-NV)")
    _faceting_options(q, d, "default: the equilibrium's with --init EQ.npz, else 1.2 x the "
                            "initial length")
    _common(q, "facet")
    d = MODEL_DEFAULTS["fch"]
    q = models.add_parser("fch", help="the functionalized curvature energy (a second-order "
                                      "energy) + length penalty")
    q.add_argument("--eta", type=finite_float,
                   help=f"functionalization parameter (default {d['eta']:g})")
    _faceting_options(q, d, "default 1.2 x the initial length")
    _common(q, "fch")
    return p


def _faceting_options(q, d, length_default):
    """``--alpha --kstar --beta --preferred-length`` of the faceting-type models."""
    q.add_argument("--alpha", type=positive_float, help=f"front width (default {d['alpha']:g})")
    q.add_argument("--kstar", type=positive_float,
                   help=f"second well kappa* (default {d['kstar']:g})")
    q.add_argument("--beta", type=nonnegative_float,
                   help=f"length penalty (default {d['beta']:g})")
    q.add_argument("--preferred-length", "--L-star", dest="L_star", metavar="LENGTH",
                   type=positive_float,
                   help=f"preferred length L* of the length penalty ({length_default})")


def _common(q, model):
    q.add_argument("--shape", choices=["paper", "wobbly", "circle"],
                   help="initial curve: the appendix trillium r = 1 + 0.35 cos 3t (+0.05 sin 4t "
                        "in x; default), a wobbly circle r = R(1 + amp cos(lobes t)), or a "
                        "circle")
    q.add_argument("--radius", type=positive_float,
                   help=f"R of wobbly/circle (default {INITIAL_DEFAULTS['radius']:g})")
    q.add_argument("--amp", type=finite_float,
                   help=f"wobble amplitude (default {INITIAL_DEFAULTS['amp']:g})")
    q.add_argument("--lobes", type=int_at_least(1),
                   help=f"wobble lobes (default {INITIAL_DEFAULTS['lobes']})")
    q.add_argument("--init", metavar="FILE",
                   help="initial curve (overrides --shape): a text file of x y rows, or a "
                        "qsa file: an equilibrium or spectrum (--save), a flow result or "
                        "checkpoint (its last state), a qsa reproduce run (its last snapshot)")
    q.add_argument("--N", type=int_at_least(8),
                   help=f"nodes (default {RUN_DEFAULTS['N']}; on --resume the checkpoint's)")
    q.add_argument("--t-final", type=positive_float,
                   help=f"final time (default {T_FINAL[model]:g}; on --resume the "
                        "checkpoint's)")
    q.add_argument("--tol", type=positive_float,
                   help=f"local error tolerance (default {RUN_DEFAULTS['tol']:g})")
    q.add_argument("--method", choices=["be", "bdf2"],
                   help="backward Euler with step doubling (the paper's; default) or BDF2")
    q.add_argument("--snapshots", type=int_at_least(2), default=None,
                   help="snapshots saved, the initial and final states included "
                        "(default 6; 60 with --movie)")
    q.add_argument("--out", metavar="DIR",
                   help="folder for result.npz, summary.json, flow.png and checkpoint.npz")
    q.add_argument("--checkpoint", metavar="FILE", default=None,
                   help="checkpoint file (default DIR/checkpoint.npz with --out)")
    q.add_argument("--resume", nargs="?", const=True, default=None, metavar="CHECKPOINT",
                   help="continue the run saved in CHECKPOINT; without a file, the "
                        "checkpoint of --out DIR (or --checkpoint FILE), as qsa reproduce "
                        "does")
    q.add_argument("--progress", action=_bool_action(), default=None,
                   help="progress bar (default: only on a terminal)")
    q.add_argument("--no-plots", action="store_true", help="no figure in --out")
    q.add_argument("--json", action="store_true", help="JSON summary on stdout")
    q.add_argument("--plot", metavar="FILE", help="write the figure to FILE")
    q.add_argument("--movie", metavar="FILE",
                   help="write an animation of the snapshots to FILE.gif (Pillow) or "
                        "FILE.mp4 (needs ffmpeg)")
    q.add_argument("--fps", type=positive_float, default=10.0,
                   help="movie frames per second (default %(default)g)")
    q.set_defaults(func=run, resume_hint=resume_hint)


def resume_hint(args, checkpoint):
    """The command that continues an interrupted flow."""
    out = f" --out {args.out}" if args.out else ""
    return f"{args.qsa_prog} --resume {checkpoint}{out}"


def _bool_action():
    import argparse

    return argparse.BooleanOptionalAction


# ---------------------------------------------------------------- initial data
def read_initial_file(path):
    """Closed samples ``(x, y)`` and the equilibrium (or None) of an ``--init`` file.

    A qsa ``.npz`` file gives its curve (an equilibrium's or spectrum's) or its last
    state (a flow result or checkpoint, a paper run's last snapshot); any other
    file is read as text rows ``x y``.

    Raises
    ------
    ValueError
        Unreadable rows, not two columns, fewer than 4 points, a NaN or inf (the
        message names the file and the row).
    """
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic == b"PK\x03\x04":  # a zip archive: a qsa file
        from qsa.flows import FlowResult
        from qsa.io import PaperRunFile, load, load_equilibrium, load_npz

        kind = load_npz(path)[1].get("kind", "")
        if kind in ("qsa.equilibrium", "qsa.spectrum"):
            eq = load_equilibrium(path)
            x, y = eq.curve.positions()
            return (x, y), eq
        result = load(path)
        if isinstance(result, FlowResult):
            return (result.x, result.y), None
        if isinstance(result, PaperRunFile) and result.has_curve:
            return (result.x, result.y), None
        raise ValueError(f"--init {path}: a {kind} file holds no curve")
    try:
        data = np.loadtxt(path, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"--init {path}: cannot read rows of two numbers x y ({exc})") from None
    if data.shape[1] != 2:
        raise ValueError(f"--init {path}: expected two columns x y, found {data.shape[1]}")
    bad = np.nonzero(~np.all(np.isfinite(data), axis=1))[0]
    if bad.size:
        raise ValueError(f"--init {path}: row {bad[0] + 1} is {data[bad[0]].tolist()} (NaN or "
                         f"inf); every row must be a finite point x y")
    if data.shape[0] < 4:
        raise ValueError(f"--init {path}: {data.shape[0]} points; a closed curve needs at "
                         "least 4")
    return (data[:, 0], data[:, 1]), None


def initial_curve(args, M=4000):
    """Samples ``(x, y)`` of the requested initial curve and its equilibrium (or None)."""
    if args.init:
        return read_initial_file(args.init)
    shape = args.shape or INITIAL_DEFAULTS["shape"]
    radius = INITIAL_DEFAULTS["radius"] if args.radius is None else args.radius
    amp = INITIAL_DEFAULTS["amp"] if args.amp is None else args.amp
    lobes = INITIAL_DEFAULTS["lobes"] if args.lobes is None else args.lobes
    th = 2 * np.pi * np.arange(M) / M
    if shape == "paper":
        r = 1 + 0.35 * np.cos(3 * th)
        return (r * np.cos(th) + 0.05 * np.sin(4 * th), r * np.sin(th)), None
    r = radius * (1 + (amp * np.cos(lobes * th) if shape == "wobbly" else 0))
    return (r * np.cos(th), r * np.sin(th)), None


def _length(xy):
    x, y = xy
    return float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))


def build_model(args, xy, eq=None):
    """The flow model of the command line (defaults: :data:`MODEL_DEFAULTS`).

    For ``facet`` from an equilibrium file, alpha, kappa*, beta and L* default to
    the equilibrium's, so the flow starts at a (discrete) rest point.
    """
    from qsa.energies import FunctionalizedCurvature, Perimeter
    from qsa.flows import CHA, FacetingFlow, SecondOrderFlow

    values = {k: getattr(args, k) for k in MODEL_DEFAULTS[args.model]}
    given = {k: MODEL_DEFAULTS[args.model][k] if v is None else v for k, v in values.items()}
    if args.model == "cha":
        return CHA(**given)
    if args.model == "fch":
        L_star = 1.2 * _length(xy) if given["L_star"] is None else given["L_star"]
        return SecondOrderFlow(FunctionalizedCurvature(given["alpha"], given["eta"],
                                                       given["kstar"])
                               + Perimeter(given["beta"], L_star))
    from_eq = dict(eq.params) if eq is not None else {}
    for k, v in values.items():
        if v is None:
            values[k] = from_eq.get(k, MODEL_DEFAULTS["facet"][k])
    if values["L_star"] is None:
        values["L_star"] = 1.2 * _length(xy)
    return FacetingFlow(**values)


# ---------------------------------------------------------------------- resume
def resume_file(args):
    """The checkpoint a bare ``--resume`` continues: ``--checkpoint``, else ``DIR/checkpoint.npz``.

    Raises
    ------
    ValueError
        One line when neither ``--out`` nor ``--checkpoint`` says where it is, or
        the file is missing.
    """
    from qsa.commands._options import check_input_file

    if args.resume is not True:
        return args.resume
    if args.checkpoint is not None:
        path = args.checkpoint
    elif args.out:
        path = os.path.join(args.out, "checkpoint.npz")
    else:
        raise ValueError("--resume: give the checkpoint (--resume FILE) or the run's "
                         "folder (--resume --out DIR)")
    check_input_file(path, "--resume")
    return path


def _saved_parameters(saved):
    """The model parameters of a checkpoint's metadata, one flat dict (energy sums merged)."""
    if "energy" not in saved:
        return saved
    energy = saved["energy"]
    values = {}
    for term in energy.get("terms", [energy]):
        values.update({k: v for k, v in term.items() if k != "energy"})
    return values


def resume_plan(args):
    """Model, N, tol, method and t_final of ``--resume``, with the options checked.

    Options that contradict the checkpoint are errors naming the option; options
    about the initial curve are ignored with a warning.
    """
    from qsa._codecs import model_from_metadata
    from qsa.io import load_npz

    path = args.resume
    arrays, meta = load_npz(path)
    if meta.get("kind") != "qsa.flow-checkpoint":
        raise ValueError(f"--resume {path}: not a flow checkpoint (kind "
                         f"{meta.get('kind')!r})")
    saved = meta["model"]
    if saved.get("model") != _MODEL_NAMES[args.model]:
        other = {v: k for k, v in _MODEL_NAMES.items()}.get(saved.get("model"), "?")
        raise ValueError(f"--resume {path}: a checkpoint of a {saved.get('model')} flow; "
                         f"continue it with qsa flow {other} --resume {path}")
    t_saved = float(meta["integrator"]["t"])
    values = _saved_parameters(saved)
    checks = {k: values.get(k) for k in MODEL_DEFAULTS[args.model]}
    checks.update({"N": int(arrays["x_setup"].size), "tol": meta["options"]["tol"],
                   "method": meta["options"]["method"]})
    for dest, value in checks.items():
        given = getattr(args, dest)
        if given is not None and given != value:
            flag = "--" + dest.replace("_", "-")
            raise ValueError(f"{flag} {given}: the checkpoint {path} was written with "
                             f"{dest}={value}; a resumed run keeps it (leave {flag} out)")
    for dest in INITIAL_OPTIONS:
        if getattr(args, dest) is not None:
            warn(args, f"--{dest} ignored: a resumed run continues from the state in {path}")
    t_final = meta.get("t_final") if args.t_final is None else args.t_final
    if t_final < t_saved * (1 - 1e-12):
        raise ValueError(f"--t-final {t_final:g}: the checkpoint {path} is at t = "
                         f"{t_saved:g}; a resumed run continues forward (give --t-final "
                         f">= {t_saved:g})")
    return {"model": model_from_metadata(saved), "N": checks["N"], "tol": checks["tol"],
            "method": checks["method"], "t_final": float(t_final), "t_saved": t_saved,
            "bound": meta.get("bound", {}), "xy": (arrays["x_setup"], arrays["y_setup"])}


# ------------------------------------------------------------------------- run
def summarize(res):
    return {
        "success": bool(res.success), "status": int(res.status), "message": res.message,
        "method": res.method, "tol": res.tol, "N": res.N, "t_final": float(res.t[-1]),
        "n_steps": res.n_steps, "n_rejected": res.n_rejected, "n_newton": res.n_newton,
        "n_lu": res.n_lu, "energy_initial": float(res.energy_steps[0]),
        "energy_final": float(res.energy_steps[-1]), "length_final": float(res.length_steps[-1]),
        "checkpoint": res.checkpoint, "model": res.system.metadata(),
    }


def _flow_memory(args, model, xy, N):
    from qsa.commands._memory import flow_bytes, require

    require(args, f"a {model.name} flow at N = {N}", flow_bytes(model, xy, N),
            "use a smaller --N")


def run(args):
    from qsa.flows import solve_flow
    from qsa.io import save_flow_result

    if args.movie:  # refuse a movie that cannot be written before running the flow
        from qsa.plotting import movie_writer

        movie_writer(args.movie)
    snapshots = args.snapshots if args.snapshots is not None else (60 if args.movie else 6)
    if args.resume:
        args.resume = resume_file(args)
        plan = resume_plan(args)
        model, N, tol, method, t_final = (plan[k] for k in ("model", "N", "tol", "method",
                                                             "t_final"))
        xy = plan["xy"]
        eq = None
    else:
        xy, eq = initial_curve(args)
        model = build_model(args, xy, eq)
        N, tol, method = (RUN_DEFAULTS[k] if getattr(args, k) is None else getattr(args, k)
                          for k in ("N", "tol", "method"))
        t_final = T_FINAL[args.model] if args.t_final is None else args.t_final
    _flow_memory(args, model, xy, N)
    checkpoint = args.checkpoint
    if args.out and checkpoint is None:
        checkpoint = os.path.join(args.out, "checkpoint.npz")
    t_eval = np.linspace(0.0, t_final, snapshots)
    res = solve_flow(model, None if args.resume else xy, t_final, N=None if args.resume else N,
                     tol=tol, method=method, t_eval=t_eval, checkpoint=checkpoint,
                     resume=args.resume, progress=args.progress)
    summary = summarize(res)
    written = []
    if args.out:
        written.append(save_flow_result(os.path.join(args.out, "result.npz"), res, summary))
        path = os.path.join(args.out, "summary.json")
        with open(path, "w") as fh:
            json.dump(summary, fh, indent=2)
        written.append(path)
    figures = [args.plot] if args.plot else []
    if args.out and not args.no_plots:
        figures.append(os.path.join(args.out, "flow.png"))
    if figures:
        from qsa.plotting import plot_flow, save

        fig = plot_flow(res, title=f"{res.system.metadata()['model']}, N = {res.N}")
        for path in figures:
            written.append(save(fig, path))
        summary["figure"] = figures[0]
    if args.movie:
        from qsa.plotting import animate_flow

        animate_flow(res, args.movie, fps=args.fps)
        summary["movie"] = args.movie
    summary["files"] = written
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{summary['model']['model']} N={res.N} {res.method} tol={res.tol:g}: "
              f"{res.message} t={summary['t_final']:.6g}, {res.n_steps} steps "
              f"({res.n_rejected} rejected), {res.n_newton} Newton iterations, "
              f"{res.n_lu} factorizations; energy {summary['energy_initial']:.6g}"
              f" -> {summary['energy_final']:.6g}")
        if written:
            print("written: " + ", ".join(written))
        if args.movie:
            print(f"movie ({len(res.t)} frames) written to {args.movie}")
    if not res.success:
        note(args, f"the flow stopped early: {res.message}")
    return 0 if res.success else 1
