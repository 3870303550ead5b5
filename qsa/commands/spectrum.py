"""``qsa spectrum npulse|splice|circle|cha``: spectrum of the linearized flow at an equilibrium.

Builds the equilibrium exactly as ``qsa equilibrium`` does (same options), then calls
:func:`qsa.spectra.spectrum` and :func:`qsa.spectra.kernel_report`. For ``cha`` (a
folded CHA state from ``--from FILE``) it reports the kernel, the unstable count and
the slowest eigenvalues outside the kernel, with their error estimates.

Examples
--------
``qsa spectrum npulse --pulses 3 --alpha 0.2 --json``
``qsa spectrum circle --radius 0.7 --alpha 0.1 --N 33 --gauge comoving --plot c.png``
``qsa spectrum npulse --pulses 3 --alpha 0.15 --fd --N 2000 --polish --k 10 --sigma 0``
``qsa spectrum npulse --pulses 3 --alpha 0.2 --save sp.npz``  (``qsa.io.load("sp.npz")``)
``qsa spectrum cha --from cha.npz --plot modes.png``  (``qsa equilibrium cha ... --save
cha.npz``; the figure: the slowest modes on the curve)
``qsa spectrum cha --from run-cha/result.npz --polish --show 4 --json``
"""

from __future__ import annotations

import json
import warnings

import numpy as np

from qsa.commands import equilibrium
from qsa.commands._errors import note
from qsa.commands._options import finite_float, int_at_least


def _extra(q):
    from qsa.spectra import GAUGES

    q.add_argument("--gauge", choices=GAUGES, default="normal",
                   help="linearization: normal (J, default), comoving (-M M^+ L_Lambda), "
                        "scaled, paper (-M M^+ grad^2 E as printed)")
    q.add_argument("--k", type=int_at_least(1), default=None,
                   help="only the k eigenvalues nearest --sigma (sparse shift-invert)")
    q.add_argument("--sigma", type=finite_float, default=None,
                   help="shift for --k (default 0)")
    q.add_argument("--no-reject", action="store_true",
                   help="skip the two-resolution spurious-mode check")
    q.add_argument("--mode", type=int_at_least(0), default=None, metavar="I",
                   help="with --plot: draw eigenmode I (index in the sorted spectrum) "
                        "instead of the spectrum")
    q.add_argument("--show", type=int_at_least(0), default=12,
                   help="eigenvalues printed (default %(default)s)")


def add_parser(sub):
    p = sub.add_parser("spectrum", help="spectrum of the linearization at an equilibrium",
                       description=__doc__.split("\n\n")[0])
    equilibrium.add_kinds(p, run, extra=_extra,
                          save="write the spectrum and its equilibrium to FILE (.npz; read it "
                               "back with qsa.io.load, the equilibrium with "
                               "qsa.io.load_equilibrium; qsa flow ... --init FILE starts from it)",
                          cha=run_cha)
    return p


def _spectrum(args, energy, curve):
    """``(Spectrum, caught warnings)`` of the command line's options at ``curve``."""
    from qsa.spectra import NotEquilibriumWarning, UnresolvedEigenvalueWarning, spectrum

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NotEquilibriumWarning)
        warnings.simplefilter("always", UnresolvedEigenvalueWarning)
        spec = spectrum(energy, curve, k=args.k, sigma=args.sigma, gauge=args.gauge,
                        reject_spurious=False if args.no_reject else None)
    return spec, caught


def run(args):
    from qsa.commands._memory import require, spectrum_bytes

    eq = equilibrium.build_polished(args)
    N = eq.curve.N
    require(args, f"the spectrum at N = {N}" + ("" if args.k is None else f" (k = {args.k})"),
            spectrum_bytes(N, fourier=not eq.curve.grid.sparse, k=args.k,
                           reject=not args.no_reject),
            "use a smaller --N, or --k K (the K eigenvalues nearest --sigma)")
    spec, caught = _spectrum(args, eq.energy, eq.curve)
    summary = {"equilibrium": eq.summary(), "spectrum": spec.summary(args.show)}
    summary["warnings"] = [str(w.message) for w in caught]
    if args.save:
        from qsa.io import save_spectrum

        summary["file"] = save_spectrum(args.save, spec, eq)
    if args.plot:
        from qsa import plotting

        if args.mode is None:
            fig = plotting.plot_spectrum(spec).figure  # all eigenvalues | those near 0
        else:
            fig = plotting.plot_eigenmode(spec, eq.curve, args.mode)
        plotting.save(fig, args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        for w in caught:
            print(f"warning: {w.message}")
        print(eq.message)
        print(spec.message)
        ev = spec.eigenvalues[: args.show]
        print(f"  {'i':>4} {'lambda':>22} {'error':>9}")
        for i, (lam, err, kern) in enumerate(zip(ev, spec.errors, spec.is_kernel, strict=False)):
            lam_s = f"{lam:.12g}" if np.isrealobj(ev) else f"{lam.real:.8g}{lam.imag:+.3g}i"
            print(f"  {i:>4} {lam_s:>22} {err:9.1e}{'  kernel' if kern else ''}")
        if spec.unresolved.size:
            print(f"  unresolved (not eigenvalues to rtol = {spec.rtol:g}): "
                  f"{np.array2string(np.real(spec.unresolved[:args.show]), precision=4)}")
        k = spec.kernel
        print(f"  kernel: dim {k.kernel_dimension} (expected {k.expected_kernel_dimension}), "
              f"|L(grad_s kappa, 0)| rel {k.lagrange_kernel:.1e}, "
              f"|grad^2E(grad_s kappa, 0)| rel {k.energy_kernel:.1e}, "
              f"small cluster {spec.n_small} (gap x{spec.gap_ratio:.3g})")
        for note in k.notes:
            print(f"  note: {note}")
        if args.plot:
            print(f"  figure written to {args.plot}")
        if args.save:
            print(f"  spectrum written to {args.save}")
    return 0 if spec.success else 1


# largest rigid-motion eigenvalue, relative to the slowest other one, of a resolved state
# (the default of qsa.paper.folded.folded_equilibrium's kernel test)
KERNEL_RESOLVE = 1e-3


def run_cha(args):
    """``qsa spectrum cha``: the spectrum at the CHA state of ``--from`` (``--polish``ed)."""
    from qsa.commands import _folded

    fe, state = _folded.build(args, spectrum=True)
    if args.polish and not fe.polished.success:
        summary = _folded.summary(fe, state, args)
        if args.json:
            print(json.dumps(summary, indent=2))
        else:
            print("\n".join(_folded.text_lines(summary)))
            print("  no spectrum: the polish failed")
        note(args, f"the polish failed, no spectrum: {fe.polished.message}")
        return 1
    fe.spectrum, caught = _spectrum(args, fe.energy, fe.curve)
    sp = fe.spectrum
    summary = _folded.summary(fe, state, args)
    summary["slowest_errors"] = [float(sp.errors[i]) for i in fe.slowest]
    summary["spectrum"] = sp.summary(args.show)
    summary["warnings"] = [str(w.message) for w in caught]
    ratio = summary.get("kernel_ratio")
    if ratio is not None and ratio > KERNEL_RESOLVE:
        # the rigid motions' eigenvalues measure the slow eigenvalues' grid error
        why = (f"the rigid motions' eigenvalues are {ratio:.1e} of the slowest |lambda| "
               f"(above {KERNEL_RESOLVE:g}): this grid does not resolve the state and its "
               f"slow eigenvalues are not to be trusted; use more nodes")
        summary.update(resolved=False, unresolved_reason=why)
        summary["warnings"].append(why)
        caught.append(warnings.WarningMessage(why, UserWarning, __file__, 0))
    summary["success"] = bool(summary["success"] and sp.success
                              and summary.get("resolved") is not False)
    if args.save:
        from qsa.io import save_spectrum

        summary["file"] = save_spectrum(args.save, sp, _folded.equilibrium_of(fe, args.polish))
    if args.plot:
        from qsa import plotting

        if args.mode is not None:
            fig = plotting.plot_eigenmode(sp, fe.curve, args.mode)
        elif args.gauge == "normal":
            from qsa.plotting.simulations import folded_modes_figure

            fig = folded_modes_figure([fe], n_modes=min(2, max(len(fe.slowest), 1)))
        else:
            fig = plotting.plot_spectrum(sp).figure
        plotting.save(fig, args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0 if summary["success"] else 1
    for w in caught:
        print(f"warning: {w.message}")
    print("\n".join(_folded.text_lines(summary)))
    print(sp.message)
    print(f"  kernel {summary['n_kernel']} (|lambda| <= {summary['kernel_tol']:.2e}), "
          f"unstable {summary['n_unstable']}: "
          f"{'stable' if summary['stable'] else 'unstable'}")
    print(f"  slowest outside the kernel:\n  {'i':>4} {'lambda':>22} {'error':>9}")
    for i in fe.slowest:
        lam = sp.eigenvalues[i]
        lam_s = f"{lam:.12g}" if np.isrealobj(lam) else f"{lam.real:.8g}{lam.imag:+.3g}i"
        print(f"  {i:>4} {lam_s:>22} {sp.errors[i]:9.1e}")
    if args.plot:
        print(f"  figure written to {args.plot}")
    if args.save:
        print(f"  spectrum written to {args.save}")
    return 0 if summary["success"] else 1
