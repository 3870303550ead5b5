"""The ``cha`` kind of ``qsa equilibrium`` and ``qsa spectrum``: a CHA state read from a file.

The state is ``--from FILE``, any of

* a CHA flow's ``result.npz`` or ``checkpoint.npz`` (``qsa flow cha --out DIR``), or a
  ``qsa reproduce folding|snowflake --out DIR`` run's checkpoint: its last state, with
  the flow's parameters and reference length ``L0``;
* a ``qsa reproduce folding|snowflake --out DIR`` run's ``<name>.npz``: its last
  snapshot, with the run's parameters and ``L0``;
* an equilibrium or spectrum file of a CHA state (``qsa equilibrium cha ... --save``,
  ``qsa spectrum cha ... --save``): its curve, with the parameters of its energy.

The energy is :func:`qsa.paper.folded.folded_energy`, ``CanhamHelfrich(eps) +
Perimeter(beta, rho L0) + Adhesion(A0, l*, a)``; ``--eps --beta --rho --A0 --l-star
--a`` replace the file's values. The nodes go onto ``Fourier(N)`` (``N`` the file's
node count or ``--N``, made odd) and, with ``--polish``, are polished by
:func:`qsa.paper.folded.folded_equilibrium`; without it the state is evaluated as read.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace

from qsa.commands._options import int_at_least, nonnegative_float, positive_float

#: The CHA parameters a file supplies and the options that replace them.
CHA_PARAMS = ("eps", "beta", "rho", "A0", "l_star", "a")
#: The terms of a CHA state's energy, in the order of ``folded_energy``.
CHA_TERMS = ("CanhamHelfrich", "Perimeter", "Adhesion")
_SOURCES = ("a CHA flow's result or checkpoint (qsa flow cha --out DIR), a qsa reproduce "
            "folding|snowflake run's <name>.npz, or qsa equilibrium|spectrum cha --save FILE")


def add_cha_kind(kinds, func, extra=None, save=None):
    """Add the ``cha`` sub-parser (its own options, then ``extra(q)``) to ``kinds``."""
    q = kinds.add_parser("cha", help="a folded CHA state (Canham-Helfrich + perimeter + "
                                     "adhesion) read from a file")
    q.add_argument("--from", dest="from", metavar="FILE", required=True,
                   help="the state: " + _SOURCES)
    q.add_argument("--eps", type=positive_float, help="bending rigidity (default: the file's)")
    q.add_argument("--beta", type=nonnegative_float,
                   help="length penalty (default: the file's)")
    q.add_argument("--rho", type=positive_float,
                   help="precompression: the length target is rho L0 (default: the file's)")
    q.add_argument("--A0", type=nonnegative_float,
                   help="adhesion strength (default: the file's)")
    q.add_argument("--kernel-length", "--l-star", dest="l_star", metavar="LENGTH",
                   type=positive_float, help="adhesion kernel length l* (default: the file's)")
    q.add_argument("--a", type=positive_float, help="kernel shape (default: the file's)")
    q.add_argument("--N", type=int_at_least(8), default=None,
                   help="nodes, on a Fourier grid (default: the file's; an even N is made "
                        "odd)")
    q.add_argument("--polish", action="store_true",
                   help="polish the state by Newton on V^n = 0 with closure (without it, "
                        "the state is evaluated as read)")
    q.add_argument("--tol", type=positive_float, default=1e-10,
                   help="relative residual target of --polish (default %(default)g)")
    q.add_argument("--maxiter", type=int_at_least(1), default=40,
                   help="Newton steps of --polish at most (default %(default)s)")
    q.add_argument("--json", action="store_true", help="JSON summary on stdout")
    q.add_argument("--plot", metavar="FILE", help="write a figure to FILE")
    if save is not None:
        q.add_argument("--save", metavar="FILE", help=save)
    if extra is not None:
        extra(q)
    q.set_defaults(func=func)
    return q


@dataclass
class CHAState:
    """A state and its CHA parameters read from a file (:func:`read_state`).

    ``curve`` is the saved curve of an equilibrium or spectrum file (taken as it is),
    else None and ``x, y`` are a flow's last nodes.
    """

    x: object
    y: object
    params: dict  # eps, beta, rho, L0, A0, l_star, a
    name: str
    source: str   # what the file is, for the text summary
    curve: object = None


def _not_cha(path, what):
    return ValueError(f"--from {path}: {what}, not a CHA state; give {_SOURCES}")


def _energy_params(eq, path):
    """The CHA parameters of an equilibrium's energy (and ``rho``, ``L0`` of its params)."""
    spec = eq.energy.params()
    terms = spec.get("terms", [spec])
    names = tuple(t.get("energy") for t in terms)
    if names != CHA_TERMS:
        raise _not_cha(path, f"an equilibrium of {' + '.join(map(str, names))}")
    ch, per, adh = terms
    rho = float(eq.params.get("rho", 1.0))
    L0 = float(eq.params.get("L0", per["L_star"] / rho))
    return {"eps": ch["eps"], "beta": per["beta"], "rho": rho, "L0": L0, "A0": adh["A0"],
            "l_star": adh["l_star"], "a": adh["a"]}


def read_state(path) -> CHAState:
    """The CHA state in ``path`` (see the module docstring for the files accepted).

    Raises
    ------
    ValueError
        One line naming ``--from`` and the file: not a qsa file, a file of another
        kind or model (e.g. a faceting equilibrium), a run without snapshot nodes.
    """
    from qsa.flows import FlowResult
    from qsa.io import PaperRunFile, load, load_equilibrium, load_npz

    with open(path, "rb") as fh:
        if fh.read(4) != b"PK\x03\x04":
            raise _not_cha(path, "a file of another format (no qsa .npz)")
    kind = load_npz(path)[1].get("kind")
    if kind in ("qsa.equilibrium", "qsa.spectrum"):
        eq = load_equilibrium(path)
        x, y = eq.curve.positions()
        name = os.path.splitext(os.path.basename(path))[0]
        return CHAState(x, y, _energy_params(eq, path), name,
                        f"{kind.split('.')[1]} file ({eq.kind})", curve=eq.curve)
    if kind not in ("qsa.flow-result", "qsa.flow-checkpoint", "qsa.paper-run"):
        raise _not_cha(path, f"a qsa file of kind {kind!r}")
    result = load(path)
    if isinstance(result, FlowResult):
        meta = result.system.metadata()
        if meta.get("model") != "CHA":
            raise _not_cha(path, f"a {meta.get('model')} flow {kind.split('-')[1]}")
        params = {k: float(meta[k]) for k in (*CHA_PARAMS, "L0")}
        return CHAState(result.x, result.y, params, "flow",
                        f"CHA flow {kind.split('-')[1]} at t = {float(result.t[-1]):.6g}")
    if isinstance(result, PaperRunFile):
        p = result.summary.get("params", {})
        if not all(k in p for k in CHA_PARAMS) or "L0" not in result.summary:
            raise _not_cha(path, f"the qsa reproduce run {result.name!r} (its summary has "
                                 "no CHA parameters and L0)")
        params = {k: float(p[k]) for k in CHA_PARAMS}
        params["L0"] = float(result.summary["L0"])
        return CHAState(result.x, result.y, params, result.name,
                        f"qsa reproduce run {result.name!r} at t = {result.t:.6g}")
    raise _not_cha(path, f"a {kind} file")  # pragma: no cover - load's kinds are above


def build(args, spectrum=False):
    """``(FoldedEquilibrium, CHAState)`` of the command line (no spectrum computed yet).

    Memory is checked first (``spectrum``: for the spectrum too). The nodes are
    resampled to ``--N`` if given (a saved curve spectrally); a state that crosses or
    touches itself is refused with the message of :func:`qsa.Curve.from_positions` or
    :func:`qsa.equilibria.polish` (the closest pair of nodes), prefixed by ``--from``.
    """
    from qsa import Curve, Fourier
    from qsa.commands._memory import polish_bytes, require, spectrum_bytes
    from qsa.paper.folded import folded_equilibrium

    path = getattr(args, "from")
    state = read_state(path)
    params = dict(state.params)
    for k in CHA_PARAMS:
        if getattr(args, k) is not None:
            params[k] = float(getattr(args, k))
    N = len(state.x) if args.N is None else args.N
    N += 1 - N % 2
    require(args, f"the CHA state at N = {N}", polish_bytes(N), "use a smaller --N")
    if spectrum:
        require(args, f"the spectrum at N = {N}" + ("" if args.k is None else
                                                     f" (k = {args.k})"),
                spectrum_bytes(N, k=args.k, reject=not args.no_reject),
                "use a smaller --N, or --k K (the K eigenvalues nearest --sigma)")
    x, y = state.x, state.y
    try:
        if state.curve is not None:   # a saved curve: resampled spectrally, if at all
            c = state.curve
            x, y = (c if c.N == N and isinstance(c.grid, Fourier) else
                    c.on_grid(Fourier(N))), None
        elif N != len(x) + 1 - len(x) % 2:   # (folded_equilibrium makes an even N odd)
            x, y = Curve.from_positions(x, y, Fourier(N)).positions()
        fe = folded_equilibrium(x, y, **params, name=state.name, tol=args.tol,
                                maxiter=args.maxiter if args.polish else 0,
                                n_slow=getattr(args, "show", 6), rate_check=False,
                                with_spectrum=False)
    except ValueError as exc:
        raise ValueError(f"--from {path}: {exc}") from None
    return fe, state


def equilibrium_of(fe, polished):
    """The :class:`~qsa.equilibria.Equilibrium` to save: the state with the CHA parameters.

    ``kind`` is ``"polished"`` after ``--polish``, else ``"cha"`` (the state as read).
    """
    pr = fe.polished
    return replace(pr, params={**pr.params, **fe.params},
                   kind="polished" if polished else "cha")


def summary(fe, state, args):
    """:meth:`FoldedEquilibrium.summary` with what the command did.

    Adds ``polished`` (whether Newton ran), ``source`` (what the file is), ``from``
    (its path) and ``message``; ``success`` is the polish's (True without ``--polish``:
    the state is only evaluated, ``polish_success`` says whether it is an equilibrium
    to ``--tol``).
    """
    out = fe.summary()
    if args.polish:
        message = fe.polished.message
    else:
        message = (f"the state as read (no Newton step; --polish solves V^n = 0): relative "
                   f"residual {fe.relative_residual:.2e}, |C(U)| = {fe.polished.closure:.2e}")
    out.update({"polished": bool(args.polish), "source": state.source,
                "from": getattr(args, "from"), "message": message,
                "success": bool(fe.polished.success) if args.polish else True})
    return out


def text_lines(s):
    """The text summary of the state (:func:`summary`)."""
    lines = [f"{s['name']}: {s['source']}", s["message"]]
    for key in ("N", "length", "energy", "relative_residual", "closure", "n_newton"):
        v = s[key]
        lines.append(f"  {key:>17} = {v:.12g}" if isinstance(v, float) else
                     f"  {key:>17} = {v}")
    lines.append("  " + ", ".join(f"{k} = {v:.6g}" for k, v in s["params"].items()))
    return lines
