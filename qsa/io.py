"""Files: atomic ``.npz`` archives with JSON metadata, loaded without pickle.

One file holds both the arrays and a JSON document (stored as the UTF-8 bytes
of the member ``__meta__.npy``), so a checkpoint is a single file that is
replaced atomically: the data are written to a temporary file in the same
folder, flushed to disk, then renamed over the target (``os.replace``). A run
killed while writing leaves the previous file intact.

Loading never unpickles (``allow_pickle=False``) and reads every member
eagerly, so a truncated or corrupted file (bad zip directory, CRC mismatch,
missing metadata) raises ``ValueError`` naming the file instead of failing
later.

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
import tempfile
import zipfile

import numpy as np

__all__ = ["save_npz", "load_npz", "json_default"]

_META = "__meta__"


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
    path = os.fspath(path)
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
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **clean)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


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
