"""Files: atomic ``.npz`` archives with JSON metadata, loaded without pickle.

One file holds both the arrays and a JSON document (stored as the UTF-8 bytes
of the member ``__meta__.npy``), so a result or a checkpoint is a single file
that is replaced atomically: the data are written to a temporary file in the
same folder, flushed to disk, then renamed over the target (``os.replace``).
A run killed while writing leaves the previous file intact. A new file gets
the permissions of the user's umask (``0o666 & ~umask``, as ``open`` gives); a
replaced file keeps its permissions.

Loading never unpickles (``allow_pickle=False``) and reads every member
eagerly, so a truncated or corrupted file (bad zip directory, CRC mismatch,
missing metadata) raises ``ValueError`` naming the file instead of failing
later. :func:`load` turns any result file qsa writes back into its result
object; :func:`load_npz` gives the raw arrays and metadata of any of them.

File layouts
------------
Every file is an ``.npz`` (zip) archive of ``.npy`` arrays plus ``__meta__``,
the JSON metadata; ``meta["kind"]`` names the layout and ``meta["version"]``
the qsa that wrote it. The fields of a result object are under a key of its
own (``meta["equilibrium"]``, ``meta["spectrum"]``, ``meta["result"]``); an
array ``a.b`` is the field ``b`` of the nested object ``a``. Arrays keep their
dtype (float64, complex128 eigenvalues, bool masks).

``qsa.equilibrium`` -- :func:`save_equilibrium`, ``qsa equilibrium ... --save FILE``
    arrays
        ``kappa``, ``g`` : shape (N,), the curve's curvature and arc-length
        density; ``multipliers`` : shape (3,), Lambda.
    ``meta["equilibrium"]``
        ``grid`` ``{"kind": "Fourier" | "FiniteDifference", "N"}``, ``theta0``,
        ``origin`` ``[x, y]`` (the curve); ``energy``: the energy's ``params()``,
        e.g. ``{"energy": "sum", "terms": [{"energy": "Faceting", "alpha",
        "kstar"}, {"energy": "Perimeter", "beta", "L_star"}]}``; ``params``
        (construction parameters: ``L``, ``L_star``, ``alpha``, ``facets``, ...);
        ``residual``, ``closure``, ``residual_scale``, ``kind`` (``"npulse"``,
        ``"splice"``, ``"circle"``, ``"polished"``, ``"cha"``), ``success``, ``message``.

``qsa.spectrum`` -- :func:`save_spectrum`, ``qsa spectrum ... --save FILE``
    arrays
        ``eigenvalues`` : (m,), ``eigenvectors`` : (n, m) (columns, normalised
        in the gauge's inner product), ``errors`` : (m,), ``is_kernel`` : (m,)
        bool, ``drift`` : (m,), ``unresolved``, ``unresolved_errors``,
        ``spurious``, ``multipliers`` : (3,); ``kernel.rigid``, ``kernel.psi``,
        ``kernel.rigid_normal``, ``kernel.multipliers`` : (3,); and the
        equilibrium the spectrum is of, as above with the prefix
        ``equilibrium.`` (``equilibrium.kappa``, ``equilibrium.g``,
        ``equilibrium.multipliers``).
    ``meta["spectrum"]``
        The other fields of :class:`~qsa.spectra.Spectrum` (``gauge``,
        ``method``, ``N``, ``N2``, ``sigma``, ``n_unstable``, ``n_kernel``,
        ``kernel_tol``, ``n_small``, ``gap_ratio``, ``roundoff``, ``rtol``,
        ``success``, ``status``, ``message``, ...); ``meta["kernel"]``: those of
        :class:`~qsa.spectra.KernelReport` (``notes`` a list);
        ``meta["equilibrium"]``: as above.

``qsa.flow-result`` -- :func:`save_flow_result`, ``qsa flow ... --out DIR`` (``DIR/result.npz``)
    arrays
        ``t`` : (n,) snapshot times; ``states`` : (n, size) full DAE states
        (blocks of N in the order of ``meta["model"]["unknowns"]``, the last
        entry L); ``energy``, ``length`` : (n,); ``t_steps``, ``energy_steps``,
        ``length_steps`` : (n_steps + 1,); ``x``, ``y`` : (N,) final nodes;
        ``x_setup``, ``y_setup`` : (N,) the nodes the system was set up from.
    ``meta["result"]``
        ``success``, ``status``, ``message``, ``method``, ``tol``, ``n_steps``,
        ``n_rejected``, ``n_newton``, ``n_factorizations``,
        ``n_newton_failures``, ``checkpoint``.
    ``meta["model"]``, ``meta["bound"]``
        ``system.metadata()`` (model name, N, parameters, unknowns) and the
        constants fixed at setup (CHA's ``L0``). The command line adds its
        summary at the top level (``N``, ``t_final``, ``energy_final``, ...).

``qsa.flow-checkpoint`` -- :func:`qsa.flows.solve_flow` ``checkpoint=``
    arrays
        ``y`` : (size,) the current state; ``x_setup``, ``y_setup`` : (N,);
        ``history_t``, ``history_y`` (BDF2's previous states), ``be_slope``,
        ``pool_c``, ``pool_y``, ``pool_ydot`` (where the Newton matrices were
        factorized, so a resumed run rebuilds the same ones),
        ``newton_theta``; ``snap_t``, ``snap_y``, ``snap_E``, ``snap_L`` (the
        snapshots so far); ``step_t``, ``step_E``, ``step_L``.
    meta
        ``model``, ``bound``, ``options`` (``method``, ``tol``),
        ``integrator`` (``t``, ``h``, counters), ``status`` (``"running"``,
        ``"interrupted"``, ``"finished"``, ``"stopped"``, ``"failed"``,
        ``"max_steps"``), ``t_final``.

``qsa.paper-run`` -- ``qsa reproduce facet|snowflake|folding --out DIR``
    The arrays of the run's ``arrays()`` (per-step series ``t``, ``energy``,
    ...; snapshots ``snap_t`` (m,), ``snap_x``, ``snap_y`` (m, N)) and its
    ``summary()`` as metadata (also in ``<name>.json``), plus ``name``.
    :func:`load` gives a :class:`PaperRunFile`.

Sweeps write one file per point; :func:`load_npz` reads them.

Examples
--------
>>> import numpy as np, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "run.npz")
>>> _ = save_npz(path, {"y": np.arange(3.0)}, {"model": "CHA", "t": 0.5})
>>> arrays, meta = load_npz(path)
>>> arrays["y"].tolist(), meta["t"]
([0.0, 1.0, 2.0], 0.5)

An equilibrium written and read back:

>>> from qsa.equilibria import circle
>>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
>>> _ = save_equilibrium(os.path.join(os.path.dirname(path), "eq.npz"), eq)
>>> back = load(os.path.join(os.path.dirname(path), "eq.npz"))
>>> type(back).__name__, bool(np.array_equal(back.curve.kappa, eq.curve.kappa))
('Equilibrium', True)
"""

from __future__ import annotations

import os

from qsa import _codecs
from qsa._version import __version__
from qsa.npz import (
    PaperRunFile,
    is_paper_run,
    json_default,
    load_npz,
    save_npz,
    write_atomically,
)

__all__ = ["save_npz", "load_npz", "json_default", "write_atomically", "load",
           "load_equilibrium", "save_equilibrium", "save_spectrum", "save_flow_result",
           "PaperRunFile"]

# ------------------------------------------------------------------ result files
def save_equilibrium(path, equilibrium, extra_meta=None):
    """Write an :class:`~qsa.equilibria.Equilibrium` (layout ``qsa.equilibrium``).

    Parameters
    ----------
    path : str or os.PathLike
    equilibrium : Equilibrium
    extra_meta : dict, optional
        More JSON metadata (e.g. the command line's summary); never overrides
        the layout's own keys.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        An energy its parameters do not describe (e.g. a custom well).
    """
    arrays, fields = _codecs.encode_equilibrium(equilibrium)
    meta = {"kind": _codecs.KIND_EQUILIBRIUM, "version": __version__, "equilibrium": fields}
    return save_npz(path, arrays, {**(extra_meta or {}), **meta})


def save_spectrum(path, spectrum, equilibrium, extra_meta=None):
    """Write a :class:`~qsa.spectra.Spectrum` with its equilibrium (layout ``qsa.spectrum``).

    Returns
    -------
    str
    """
    arrays, meta = _codecs.encode_spectrum(spectrum, equilibrium)
    return save_npz(path, arrays, {**(extra_meta or {}), **meta})


def save_flow_result(path, result, extra_meta=None):
    """Write a :class:`~qsa.flows.FlowResult` (layout ``qsa.flow-result``).

    Returns
    -------
    str
    """
    arrays, meta = _codecs.encode_flow_result(result)
    return save_npz(path, arrays, {**(extra_meta or {}), **meta})


def load(path):
    """The result object stored in a file qsa wrote.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Equilibrium, Spectrum, FlowResult or PaperRunFile
        By the file's kind: ``qsa.equilibrium`` -> Equilibrium, ``qsa.spectrum``
        -> Spectrum (its equilibrium: :func:`load_equilibrium`),
        ``qsa.flow-result`` and ``qsa.flow-checkpoint`` -> FlowResult (a
        checkpoint gives the run up to its time), ``qsa.paper-run`` (a
        ``qsa reproduce`` run's ``<name>.npz``) -> :class:`PaperRunFile`.

    Raises
    ------
    ValueError
        A missing or damaged file, or one whose kind has no result object (a
        sweep point, a run's series: read those with :func:`load_npz`).
    """
    arrays, meta = load_npz(path)
    kind = meta.get("kind")
    if is_paper_run(meta):
        summary = {k: v for k, v in meta.items() if k not in ("kind", "name")}
        name = meta.get("name", meta.get("scenario", os.path.splitext(os.path.basename(
            os.fspath(path)))[0]))
        return PaperRunFile(os.fspath(path), str(name), summary, arrays)
    try:
        if kind == _codecs.KIND_EQUILIBRIUM:
            return _codecs.decode_equilibrium(arrays, meta["equilibrium"])
        if kind == _codecs.KIND_SPECTRUM:
            return _codecs.decode_spectrum(arrays, meta)
        if kind == _codecs.KIND_FLOW_RESULT:
            return _codecs.decode_flow_result(arrays, meta)
        if kind == _codecs.KIND_FLOW_CHECKPOINT:
            return _codecs.decode_flow_checkpoint(arrays, meta, os.fspath(path))
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{os.fspath(path)}: a {kind} file with missing or bad fields "
                         f"({type(exc).__name__}: {exc})") from None
    what = f"kind {kind!r}" if kind else "no 'kind' (a paper run's data or an older file)"
    raise ValueError(f"{os.fspath(path)}: a qsa file of {what}, which has no result object; "
                     "read its arrays and metadata with qsa.io.load_npz")


def load_equilibrium(path):
    """The :class:`~qsa.equilibria.Equilibrium` in an equilibrium or spectrum file.

    Raises
    ------
    ValueError
        A file of another kind.
    """
    arrays, meta = load_npz(path)
    kind = meta.get("kind")
    prefixes = {_codecs.KIND_EQUILIBRIUM: "", _codecs.KIND_SPECTRUM: "equilibrium"}
    if kind in prefixes:
        return _codecs.decode_equilibrium(arrays, meta["equilibrium"], prefixes[kind])
    raise ValueError(f"{os.fspath(path)}: holds no equilibrium (kind {kind!r})")
