"""Animations of curve flows (``matplotlib.animation``): GIF with Pillow, MP4 with ffmpeg."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import animation

from qsa.plotting._core import new_figure

__all__ = ["animate_flow", "movie_writer"]

#: File extension -> matplotlib writer name.
WRITERS = {".gif": "pillow", ".mp4": "ffmpeg"}


def movie_writer(path) -> str:
    """The writer for a movie file: ``"pillow"`` for ``.gif``, ``"ffmpeg"`` for ``.mp4``.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Another extension, or ``.mp4`` without ffmpeg on the ``PATH``.

    Examples
    --------
    >>> movie_writer("flow.gif")
    'pillow'
    """
    ext = Path(path).suffix.lower()
    if ext not in WRITERS:
        raise ValueError(f"movie {path}: the file must end in .gif or .mp4, got {ext or 'none'!r}")
    name = WRITERS[ext]
    if not animation.writers.is_available(name):
        raise ValueError(f"movie {path}: writing {ext} needs {name}, which is not installed; "
                         "write a .gif instead (Pillow comes with matplotlib)")
    return name


def animate_flow(result, path=None, fps=10, dpi=100, title=None):
    """Animate a flow: the curve at each snapshot (left), the energy up to that time (right).

    Parameters
    ----------
    result : FlowResult
        From :func:`qsa.flows.solve_flow`; one frame per snapshot (``result.t``; ask
        ``solve_flow`` for them with ``t_eval``).
    path : str or Path, optional
        Write the movie there (``.gif`` with Pillow, ``.mp4`` with ffmpeg).
    fps : float
        Frames per second.
    dpi : float
        Resolution of the written frames.
    title : str, optional
        Figure title (default: the model and N).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        ``len(result.t)`` frames; ``.save`` writes it again in another format.

    Raises
    ------
    ValueError
        ``fps <= 0``, fewer than two snapshots, or an unsupported ``path`` (see
        :func:`movie_writer`).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.flows import FacetingFlow, solve_flow
    >>> th = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    >>> r = 1 + 0.05 * np.cos(5 * th)
    >>> res = solve_flow(FacetingFlow(0.1, 5.0, 5.0, 7.0), (r * np.cos(th), r * np.sin(th)),
    ...                  1e-4, N=64, t_eval=np.linspace(0, 1e-4, 5), progress=False)
    >>> import os, tempfile
    >>> from PIL import Image
    >>> path = os.path.join(tempfile.mkdtemp(), "flow.gif")
    >>> anim = animate_flow(res, path)
    >>> Image.open(path).n_frames
    5
    """
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be positive, got {fps!r}")
    n = len(result.t)
    if n < 2:
        raise ValueError("result has fewer than two snapshots: pass t_eval to solve_flow")
    writer = movie_writer(path) if path is not None else None
    xy = [result.positions(i) for i in range(n)]
    xs = np.concatenate([p[0] for p in xy])
    ys = np.concatenate([p[1] for p in xy])
    pad = 0.05 * max(np.ptp(xs), np.ptp(ys))
    fig, (ax, ax_e) = new_figure(ncols=2, size=(4.2, 3.8))
    ax.set_xlim(xs.min() - pad, xs.max() + pad)
    ax.set_ylim(ys.min() - pad, ys.max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    (first,) = ax.plot([], [], color="0.75", lw=1.0, label=f"t = {result.t[0]:.3g}")
    (curve,) = ax.plot([], [], color="C0", lw=1.6)
    x0, y0 = xy[0]
    first.set_data(np.append(x0, x0[0]), np.append(y0, y0[0]))
    ax.legend(fontsize="small", loc="upper right")
    label = ax.text(0.03, 0.03, "", transform=ax.transAxes, fontsize="small")
    t_steps, e_steps = np.asarray(result.t_steps), np.asarray(result.energy_steps)
    ax_e.plot(t_steps, e_steps, color="0.8", lw=1.0)
    (trace,) = ax_e.plot([], [], color="C0", lw=1.6)
    (dot,) = ax_e.plot([], [], "o", color="C3", ms=5)
    ax_e.set_xlabel("t")
    ax_e.set_ylabel("energy")
    fig.suptitle(title or f"{result.system.metadata().get('model', 'flow')}, N = {result.N}")

    def draw(i):
        x, y = xy[i]
        curve.set_data(np.append(x, x[0]), np.append(y, y[0]))
        label.set_text(f"t = {result.t[i]:.4g}")
        upto = t_steps <= result.t[i] * (1 + 1e-12)
        trace.set_data(t_steps[upto], e_steps[upto])
        dot.set_data([result.t[i]], [result.energy[i]])
        return curve, label, trace, dot

    anim = animation.FuncAnimation(fig, draw, frames=n, interval=1000.0 / fps, blit=False,
                                   repeat=False, cache_frame_data=False)
    if path is not None:
        anim.save(str(path), writer=writer, fps=fps, dpi=dpi)
    return anim
