"""Spectra and eigenmodes (:mod:`qsa.spectra`): eigenvalue plots, kappa1(s), perturbed curves."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import FixedLocator, FuncFormatter, MaxNLocator, NullLocator

from qsa import geometry
from qsa.plotting._core import figure_pair, new_figure, plot_curve

__all__ = ["plot_spectrum", "plot_eigenmode", "eigenmode_fields", "near_zero_indices"]

_STYLE = {"stable": ("C0", "o"), "unstable": ("C3", "o"), "kernel": ("C1", "D")}


def near_zero_indices(spec, max_count=16):
    """Indices (into ``spec.eigenvalues``) of the eigenvalues nearest 0 worth a close look.

    The kernel, the unstable eigenvalues and the cluster of small eigenvalues
    (``n_small``): the ``max(n_small, n_kernel + n_unstable)`` eigenvalues smallest in
    modulus, at least ``min(3, m)`` and at most ``max_count``; sorted by index.

    Parameters
    ----------
    spec : Spectrum
    max_count : int

    Returns
    -------
    ndarray of int

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import spectrum
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> s = spectrum(eq.energy, eq.curve)
    >>> s.n_small  # the translations and the double lambda_2 = -4.86
    4
    >>> near_zero_indices(s).tolist()
    [0, 1, 2, 3]
    """
    ev = spec.eigenvalues
    slow = max(int(spec.n_small), int(spec.n_kernel) + int(spec.n_unstable))
    count = int(min(ev.size, max(min(3, ev.size), min(slow, max_count))))
    return np.sort(np.argsort(np.abs(ev), kind="stable")[:count])


def _classes(spec, ev):
    """Boolean masks ``(stable, unstable, kernel)`` of the eigenvalues ``ev``."""
    m = ev.size
    is_kernel = np.asarray(spec.is_kernel[:m], bool) if spec.is_kernel.size >= m else (
        np.zeros(m, bool))
    kernel = is_kernel | (np.abs(ev) <= spec.kernel_tol)
    unstable = (np.real(ev) > spec.kernel_tol) & ~kernel
    return ~(kernel | unstable), unstable, kernel


def _symlog_axis(axis, values, linthresh):
    """A symlog axis whose linear part (``|x| <= linthresh``) holds the eigenvalues near 0.

    The linear part gets about a sixth of the axis and the ticks are ``0`` and
    ``+-10^k`` (every ``step``-th decade, at most about four per side), so no two labels
    share a place.
    """
    values = np.asarray(values, float)
    k0 = int(round(np.log10(linthresh)))
    top = {}
    for sign in (1, -1):
        side = values[sign * values > linthresh]
        top[sign] = int(np.ceil(np.log10(np.max(np.abs(side))))) if side.size else k0
    decades = (top[1] - k0) + (top[-1] - k0)
    step = int(max(1, np.ceil(max(top[1], top[-1]) - k0) / 4))
    ticks = [0.0]
    for sign in (1, -1):
        ticks += [sign * 10.0 ** k for k in range(k0, top[sign] + 1, step)]
    name = "x" if axis.axis_name == "x" else "y"
    getattr(axis.axes, f"set_{name}scale")("symlog", linthresh=linthresh,
                                           linscale=max(0.5, decades / 10))
    axis.set_major_locator(FixedLocator(sorted(ticks)))
    axis.set_minor_locator(NullLocator())

    def label(x, _pos):
        if x == 0:
            return "0"
        return ("\u2212" if x < 0 else "") + f"$10^{{{int(round(np.log10(abs(x))))}}}$"

    axis.set_major_formatter(FuncFormatter(label))


def plot_spectrum(spec, ax=None, title=None, max_eigenvalues=None, near_zero=True):
    """Eigenvalues of a :class:`~qsa.spectra.Spectrum`: all of them, and those near 0.

    Left panel, real spectra: ``lambda`` against its index (most unstable first) on a
    symmetric-log axis whose linear part holds the eigenvalues near 0 (shaded);
    unstable modes red, kernel modes (the deflated rigid motions and
    ``|lambda| <= kernel_tol``) orange diamonds, the rejected spurious eigenvalues grey
    crosses (placed after the kept ones). Complex spectra (``"paper"`` gauge): the
    complex plane, symmetric-log real axis. Right panel (``near_zero``): the
    eigenvalues nearest 0 (:func:`near_zero_indices`) on a linear axis, with their
    error estimates (``Spectrum.errors``) as error bars. Unresolved eigenvalue
    estimates are not eigenvalues and are not drawn; the title counts them.

    Parameters
    ----------
    spec : Spectrum
    ax : Axes or pair of Axes, optional
        Where to draw: a pair (overview, near 0), or one Axes for the overview only.
        Default: a new two-panel figure (one panel if ``near_zero`` is False).
    title : str, optional
    max_eigenvalues : int, optional
        Show only the first ``max_eigenvalues`` (largest real part).
    near_zero : bool
        Draw the near-zero panel (when a new figure is made).

    Returns
    -------
    Axes
        The overview panel (``.figure`` is the figure).

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import spectrum
    >>> from qsa.plotting import plot_spectrum
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> ax = plot_spectrum(spectrum(eq.energy, eq.curve))
    >>> [a.get_ylabel() for a in ax.figure.axes]
    ['$\\\\lambda$', '$\\\\lambda$ (near 0)']
    """
    if ax is None:
        _, axes = new_figure(ncols=2 if near_zero else 1, size=(5.0, 4.0))
        axes = list(np.atleast_1d(axes))
    else:
        axes = list(ax) if isinstance(ax, (list, tuple, np.ndarray)) else [ax]
    main = axes[0]
    zoom = axes[1] if len(axes) > 1 else None
    ev = spec.eigenvalues if max_eigenvalues is None else spec.eigenvalues[:max_eigenvalues]
    masks = dict(zip(("stable", "unstable", "kernel"), _classes(spec, ev), strict=True))
    near = near_zero_indices(spec)
    near = near[near < ev.size]
    scale = float(np.max(np.abs(ev[near]))) if near.size else 1.0
    linthresh = 10.0 ** np.ceil(np.log10(max(scale, spec.kernel_tol, 1e-12)))
    if np.iscomplexobj(ev):
        _plot_complex(spec, ev, masks, main, zoom, near, linthresh)
    else:
        _plot_real(spec, ev, masks, main, zoom, near, linthresh, max_eigenvalues)
    extra = f", {spec.unresolved.size} unresolved (not shown)" if spec.unresolved.size else ""
    text = title or (f"{spec.gauge} gauge, N = {spec.N}: {spec.n_unstable} unstable, "
                     f"{spec.n_kernel} kernel{extra}")
    if zoom is not None and title is None:
        main.figure.suptitle(text)
    else:
        main.set_title(text)
    return main


def _plot_real(spec, ev, masks, main, zoom, near, linthresh, max_eigenvalues):
    idx = np.arange(ev.size)
    for lab, mask in masks.items():
        col, mk = _STYLE[lab]
        main.plot(idx[mask], ev[mask], mk, ms=4, color=col, label=f"{lab} ({mask.sum()})")
    if spec.spurious.size and max_eigenvalues is None:
        j = ev.size + np.arange(spec.spurious.size)
        main.plot(j, np.real(spec.spurious), "x", ms=4, color="0.5",
                  label=f"spurious ({spec.spurious.size})")
    values = np.concatenate([ev, np.real(spec.spurious)]) if spec.spurious.size else ev
    _symlog_axis(main.yaxis, values, linthresh)
    main.axhline(0.0, color="k", lw=0.5)
    main.axhspan(-linthresh, linthresh, color="0.92", zorder=0,
                 label="linear part" if zoom is None else "shown at right")
    main.set_xlabel("index (most unstable first)")
    main.set_ylabel(r"$\lambda$")
    main.legend(fontsize="small", loc="lower left")
    if zoom is None or near.size == 0:
        return
    err = np.asarray(spec.errors[: ev.size], float)
    for lab, mask in masks.items():
        sel = near[mask[near]]
        if sel.size == 0:
            continue
        col, mk = _STYLE[lab]
        zoom.errorbar(sel, ev[sel], yerr=err[sel], fmt=mk, ms=5, color=col, capsize=3,
                      label=lab)
    zoom.axhline(0.0, color="k", lw=0.5)
    zoom.set_xlabel("index")
    zoom.set_ylabel(r"$\lambda$ (near 0)")
    zoom.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4), useMathText=True)
    zoom.xaxis.set_major_locator(MaxNLocator(integer=True))
    zoom.set_title(f"the {near.size} eigenvalues nearest 0 (bars: error estimates)",
                   fontsize="medium")
    rest = np.setdiff1d(idx, near)
    if rest.size:
        nxt = rest[np.argmin(np.abs(ev[rest]))]
        zoom.text(0.98, 0.03, rf"next: $\lambda_{{{nxt}}}$ = {ev[nxt]:.4g}",
                  transform=zoom.transAxes, ha="right", va="bottom", fontsize="small")
    zoom.margins(x=0.15, y=0.15)
    zoom.legend(fontsize="small", loc="best")


def _plot_complex(spec, ev, masks, main, zoom, near, linthresh):
    for lab, mask in masks.items():
        col, mk = _STYLE[lab]
        main.plot(ev[mask].real, ev[mask].imag, mk, ms=4, color=col, label=lab)
    _symlog_axis(main.xaxis, np.real(ev), linthresh)
    main.set_xlabel(r"Re $\lambda$")
    main.set_ylabel(r"Im $\lambda$")
    main.legend(fontsize="small")
    if zoom is None or near.size == 0:
        return
    for lab, mask in masks.items():
        sel = near[mask[near]]
        col, mk = _STYLE[lab]
        zoom.plot(ev[sel].real, ev[sel].imag, mk, ms=5, color=col, label=lab)
    zoom.axvline(0.0, color="k", lw=0.5)
    zoom.set_xlabel(r"Re $\lambda$ (near 0)")
    zoom.set_ylabel(r"Im $\lambda$")
    zoom.ticklabel_format(style="sci", scilimits=(-3, 4), useMathText=True)
    zoom.set_title(f"the {near.size} eigenvalues nearest 0", fontsize="medium")


def eigenmode_fields(spec, curve, index=0):
    """``(phi, kappa1)`` of eigenvector ``index``: normal displacement and curvature change.

    ``"normal"`` gauge: ``kappa1 = G phi = [M(phi, 0)]_kappa``; ``"comoving"``/``"paper"``:
    ``phi = None`` and ``kappa1`` the first half of the eigenvector; ``"scaled"``:
    ``phi = None``, ``kappa1`` the first N entries. Real parts are taken.
    """
    if not 0 <= index < spec.eigenvalues.size:
        raise ValueError(f"index must be in [0, {spec.eigenvalues.size}), got {index}")
    v = np.real(spec.eigenvectors[:, index])
    N = curve.N
    if spec.gauge == "normal":
        return v, geometry.M(curve)[:N, :N] @ v
    return None, v[:N]


def plot_eigenmode(spec, curve, index=0, amplitude=None, axes=None, title=None):
    """Eigenmode ``index`` of ``spec``: ``kappa1(s)`` (left) and the perturbed curve (right).

    Parameters
    ----------
    spec : Spectrum
    curve : Curve
        The curve the spectrum was computed at.
    index : int
        Position in ``spec.eigenvalues``.
    amplitude : float, optional
        Size of the displayed perturbation (default 8 % of the curve's diameter for
        normal modes; for intrinsic modes ``U + a U1`` with ``a`` such that
        ``max |a kappa1| = 0.3 max |kappa|``).
    axes : pair of Axes, optional
    title : str, optional

    Returns
    -------
    Figure
    """
    fig, axes = figure_pair(axes)
    phi, k1 = eigenmode_fields(spec, curve, index)
    s = curve.grid.s
    lam = spec.eigenvalues[index]
    axes[0].plot(np.append(s, 1), np.append(k1, k1[0]), color="C3", lw=1.2,
                 label=r"$\kappa_1$")
    if phi is not None:
        scale = np.max(np.abs(k1)) / max(np.max(np.abs(phi)), 1e-300)
        axes[0].plot(np.append(s, 1), scale * np.append(phi, phi[0]), color="C0", lw=1.0,
                     ls="--", label=rf"$\varphi$ (x{scale:.3g})")
    axes[0].set_xlabel("s")
    axes[0].set_ylabel(r"curvature change $\kappa_1$" if phi is None
                       else r"$\kappa_1$ and normal displacement $\varphi$")
    axes[0].set_xlim(0, 1)
    axes[0].legend(fontsize="small")
    plot_curve(curve, axes[1], color="0.6", mark_start=False)
    x, y = curve.positions()
    if phi is not None:
        a = amplitude if amplitude is not None else (
            0.08 * np.ptp(x) / max(np.max(np.abs(phi)), 1e-300))
        n = curve.normal()
        xp, yp = x + a * phi * n[0], y + a * phi * n[1]
    else:
        N = curve.N
        v = np.real(spec.eigenvectors[:, index])
        a = amplitude if amplitude is not None else (
            0.3 * np.max(np.abs(curve.kappa)) / max(np.max(np.abs(v[:N])), 1e-300))
        g1 = v[N:] if v.size == 2 * N else np.full(N, v[N])
        xp, yp = curve.with_U(curve.U + a * np.concatenate([v[:N], g1])).positions()
    axes[1].plot(np.append(xp, xp[0]), np.append(yp, yp[0]), color="C3", lw=1.5)
    fig.suptitle(title or rf"mode {index}: $\lambda$ = {complex(lam).real:.6g}"
                 + (f" {complex(lam).imag:+.3g}i" if np.iscomplexobj(lam) else ""))
    return fig
