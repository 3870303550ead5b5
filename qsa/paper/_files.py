"""Files of the paper runs: ``<name>.npz`` + ``<name>.json`` and the resumable series."""

from __future__ import annotations

import json
import os
import time

import numpy as np

from qsa.npz import KIND_PAPER_RUN, json_default, load_npz, save_npz

__all__ = ["write_output", "Series", "checkpoint_time", "checkpoint_nodes"]


class _Summarised:
    """``to_json()`` for results with a ``summary()``."""

    def to_json(self, indent=2):
        """``summary()`` as JSON text."""
        return json.dumps(self.summary(), indent=indent, default=json_default)


def write_output(out, name, arrays, summary):
    """Write ``<out>/<name>.npz`` (atomic, no pickle) and ``<out>/<name>.json``; return paths."""
    os.makedirs(out, exist_ok=True)
    npz = save_npz(os.path.join(out, f"{name}.npz"), arrays,
                   {**summary, "kind": KIND_PAPER_RUN, "name": name})
    path = os.path.join(out, f"{name}.json")
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(summary, fh, indent=2, default=json_default)
        fh.write("\n")
    os.replace(tmp, path)
    return [npz, path]


class Series:
    """Per-step diagnostics recorded by a ``solve_flow`` callback, saved for resuming."""

    def __init__(self, names, path=None, interval=10.0):
        self.names = names
        self.data = {n: [] for n in ("t",) + tuple(names)}
        self.path, self.interval, self._last = path, interval, time.monotonic()

    def append(self, t, **values):
        self.data["t"].append(float(t))
        for n in self.names:
            self.data[n].append(float(values[n]))
        if self.path is not None and time.monotonic() - self._last >= self.interval:
            self.save()

    def save(self):
        if self.path is not None:
            save_npz(self.path, self.arrays(), {"kind": "qsa.run-series"})
            self._last = time.monotonic()

    def load(self, t_max):
        """Restore the saved series up to time ``t_max`` (the resumed checkpoint's time)."""
        if self.path is None or not os.path.isfile(self.path):
            return
        arrays, _ = load_npz(self.path)
        keep = arrays["t"] <= t_max * (1 + 1e-12)
        for n in self.data:
            self.data[n] = [float(v) for v in arrays[n][keep]]

    def arrays(self):
        return {n: np.asarray(v, dtype=float) for n, v in self.data.items()}


def checkpoint_time(path):
    """Time of the last step stored in a ``solve_flow`` checkpoint."""
    arrays, _ = load_npz(path)
    return float(arrays["step_t"][-1])


def checkpoint_nodes(path):
    """Number of nodes of the run stored in a ``solve_flow`` checkpoint."""
    arrays, _ = load_npz(path)
    return int(arrays["x_setup"].size)
