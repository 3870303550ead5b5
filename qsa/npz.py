"""Atomic ``.npz`` archives with JSON metadata, read without pickle (the files' lowest layer).

:func:`save_npz` writes a dict of arrays and a JSON document (the UTF-8 bytes of
the member ``__meta__.npy``) into one file, replaced atomically
(:func:`write_atomically`: a temporary file in the same folder, flushed, then
renamed over the target), with the user's umask for a new file and the old
mode for a replaced one. :func:`load_npz` reads every member eagerly with
``allow_pickle=False`` and turns a damaged file into a ``ValueError`` naming it.
The result-level functions and the file layouts are in :mod:`qsa.io`.

Examples
--------
>>> import numpy as np, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "run.npz")
>>> _ = save_npz(path, {"y": np.arange(3.0)}, {"model": "CHA", "t": 0.5})
>>> arrays, meta = load_npz(path)
>>> arrays["y"].tolist(), meta["t"]
([0.0, 1.0, 2.0], 0.5)
"""

from __future__ import annotations

import json
import os
import secrets
import zipfile
from dataclasses import dataclass, field

import numpy as np

__all__ = ["save_npz", "load_npz", "json_default", "write_atomically", "KIND_PAPER_RUN",
           "PaperRunFile"]

#: ``meta["kind"]`` of a paper run's ``<name>.npz`` (``qsa reproduce``).
KIND_PAPER_RUN = "qsa.paper-run"


@dataclass(frozen=True, eq=False)
class PaperRunFile:
    """A paper run's ``<name>.npz`` read back: its summary and its arrays.

    The runs of ``qsa reproduce`` store what their printed summary and figures
    need, not a whole flow, so this record gives them as they are, plus the
    nodes of the run's last snapshot when the run stored them (``snap_x``,
    ``snap_y``) -- the curve to polish or to take a spectrum of.

    Attributes
    ----------
    path : str
    name : str
        The run's file stem (``"facet"``, ``"cha_rho1.5"``, ...).
    summary : dict
        The run's JSON summary (the same as ``<name>.json``).
    arrays : dict of str to ndarray
    """

    path: str
    name: str
    summary: dict
    arrays: dict = field(repr=False)

    @property
    def has_curve(self) -> bool:
        """Whether the file holds the nodes of its snapshots."""
        return "snap_x" in self.arrays and len(self.arrays["snap_x"]) > 0

    def _snapshot(self, key):
        if not self.has_curve:
            raise ValueError(f"{self.path}: the run {self.name!r} stored no snapshot nodes "
                             "(snap_x, snap_y); run it again with this version of qsa")
        return np.asarray(self.arrays[key][-1], dtype=float)

    @property
    def x(self) -> np.ndarray:
        """Nodes ``x`` of the last snapshot, shape (N,)."""
        return self._snapshot("snap_x")

    @property
    def y(self) -> np.ndarray:
        """Nodes ``y`` of the last snapshot, shape (N,)."""
        return self._snapshot("snap_y")

    @property
    def t(self) -> float:
        """Time of the last snapshot."""
        return float(np.asarray(self.arrays["snap_t"])[-1])


def is_paper_run(meta) -> bool:
    """Whether metadata are a paper run's (its kind, or a summary written before kinds)."""
    return meta.get("kind") == KIND_PAPER_RUN or ("kind" not in meta and "scenario" in meta)


_META = "__meta__"


def write_atomically(path, write):
    """Create or replace ``path`` atomically with what ``write(fh)`` writes.

    The data go to a temporary file in the same folder (created with mode
    ``0o666``, so the umask applies, or with the mode of the file it replaces),
    are flushed to disk, then renamed over ``path``.

    Parameters
    ----------
    path : str or os.PathLike
    write : callable
        ``write(fh)`` with ``fh`` a binary file open for writing.

    Returns
    -------
    str
        The path written.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    try:
        mode = os.stat(path).st_mode & 0o7777
    except OSError:
        mode = None
    while True:
        tmp = os.path.join(folder, f".{os.path.basename(path)}.{secrets.token_hex(6)}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
            break
        except FileExistsError:  # pragma: no cover - a 48-bit name collision
            continue
    try:
        if mode is not None:
            os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def save_npz(path, arrays, meta):
    """Write ``arrays`` (name -> ndarray) and the JSON-serialisable ``meta`` atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (conventionally ``.npz``; written exactly at this path).
    arrays : dict of str -> array_like
        Numeric arrays (object arrays are refused: they would need pickle).
    meta : dict
        JSON-serialisable metadata (NumPy scalars are converted).

    Returns
    -------
    str
        The path written.
    """
    if _META in arrays:
        raise ValueError(f"arrays: the name {_META!r} is reserved for the metadata")
    clean = {}
    for name, value in arrays.items():
        a = np.asarray(value)
        if a.dtype == object:
            raise ValueError(f"arrays[{name!r}] has dtype object; only numeric arrays are stored")
        clean[name] = a
    text = json.dumps(meta, default=json_default, allow_nan=True)
    clean[_META] = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    return write_atomically(path, lambda fh: np.savez(fh, **clean))


def load_npz(path):
    """Read a file written by :func:`save_npz`.

    Returns
    -------
    arrays : dict of str -> ndarray
    meta : dict

    Raises
    ------
    ValueError
        If the file is missing, truncated, corrupted or not written by
        :func:`save_npz`.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError,
            zipfile.LargeZipFile) as exc:
        raise ValueError(f"{path}: corrupt or truncated file ({type(exc).__name__}: {exc})") \
            from None
    if _META not in arrays:
        raise ValueError(f"{path}: not a qsa file (no {_META!r} metadata member)")
    try:
        meta = json.loads(arrays.pop(_META).tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: corrupt metadata ({exc})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: corrupt metadata (not a JSON object)")
    return arrays, meta


def json_default(value):
    """``json.dump(default=...)`` for NumPy scalars and arrays (anything else: TypeError)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")
