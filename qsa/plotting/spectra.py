"""Spectra and eigenmodes (:mod:`qsa.spectra`): eigenvalue plots, kappa1(s), perturbed curves."""

from __future__ import annotations

import numpy as np

from qsa import geometry
from qsa.plotting._core import figure_pair, new_figure, plot_curve

__all__ = ["plot_spectrum", "plot_eigenmode", "eigenmode_fields"]


def plot_spectrum(spec, ax=None, title=None, max_eigenvalues=None):
    """Eigenvalues of a :class:`~qsa.spectra.Spectrum`.

    Real spectra: ``lambda`` against its index (most unstable first) on a symlog
    axis, unstable modes red, kernel modes (``|lambda| <= kernel_tol``) orange, the
    rejected spurious eigenvalues grey crosses (placed after the kept ones).
    Complex spectra (``"paper"`` gauge): the complex plane, symlog real axis.

    Parameters
    ----------
    spec : Spectrum
    ax : Axes, optional
    title : str, optional
    max_eigenvalues : int, optional
        Show only the first ``max_eigenvalues`` (largest real part).

    Returns
    -------
    Axes
    """
    if ax is None:
        _, ax = new_figure(size=(6.0, 4.0))
    ev = spec.eigenvalues if max_eigenvalues is None else spec.eigenvalues[:max_eigenvalues]
    tol = spec.kernel_tol
    kernel = np.abs(ev) <= tol
    unstable = np.real(ev) > tol
    rest = ~(kernel | unstable)
    linthresh = max(tol, 1e-8)
    if np.iscomplexobj(ev):
        for mask, col, lab in ((rest, "C0", "stable"), (unstable, "C3", "unstable"),
                               (kernel, "C1", "kernel")):
            ax.plot(ev[mask].real, ev[mask].imag, "o", ms=4, color=col, label=lab)
        ax.set_xscale("symlog", linthresh=linthresh)
        ax.set_xlabel(r"Re $\lambda$")
        ax.set_ylabel(r"Im $\lambda$")
    else:
        idx = np.arange(ev.size)
        for mask, col, lab in ((rest, "C0", "stable"), (unstable, "C3", "unstable"),
                               (kernel, "C1", "kernel")):
            ax.plot(idx[mask], ev[mask], "o", ms=4, color=col, label=f"{lab} ({mask.sum()})")
        if spec.spurious.size and max_eigenvalues is None:
            j = ev.size + np.arange(spec.spurious.size)
            ax.plot(j, np.real(spec.spurious), "x", ms=4, color="0.5",
                    label=f"spurious ({spec.spurious.size})")
        ax.set_yscale("symlog", linthresh=linthresh)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("index")
        ax.set_ylabel(r"$\lambda$")
    ax.legend(fontsize="small")
    ax.set_title(title or f"{spec.gauge} gauge, N = {spec.N}: {spec.n_unstable} unstable, "
                          f"{spec.n_kernel} kernel")
    return ax


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
