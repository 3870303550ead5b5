"""Atomic npz + JSON files: round trip, no pickle, clear errors for damaged files."""

import numpy as np
import pytest

from qsa.io import load_npz, save_npz


def test_round_trip_and_atomic_replace(tmp_path):
    path = tmp_path / "a.npz"
    save_npz(path, {"y": np.arange(5.0), "k": np.array([1, 2])}, {"t": 0.25, "name": "CHA",
                                                                    "n": np.int64(3)})
    save_npz(path, {"y": np.arange(6.0)}, {"t": 0.5})  # replaced in one rename
    arrays, meta = load_npz(path)
    assert meta == {"t": 0.5}
    np.testing.assert_array_equal(arrays["y"], np.arange(6.0))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz"]  # no temporary left


def test_object_arrays_and_reserved_names_are_refused(tmp_path):
    with pytest.raises(ValueError, match="dtype object"):
        save_npz(tmp_path / "b.npz", {"o": np.array([{"a": 1}], dtype=object)}, {})
    with pytest.raises(ValueError, match="reserved"):
        save_npz(tmp_path / "b.npz", {"__meta__": np.zeros(1)}, {})
    assert not (tmp_path / "b.npz").exists()


def test_damaged_files_raise_value_error(tmp_path):
    good = tmp_path / "good.npz"
    save_npz(good, {"y": np.random.default_rng(0).standard_normal(5000)}, {"t": 1.0})
    data = good.read_bytes()
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(data[: len(data) // 2])
    flipped = tmp_path / "flipped.npz"
    mid = len(data) // 2
    flipped.write_bytes(data[:mid] + bytes([data[mid] ^ 0xFF]) + data[mid + 1 :])
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    plain = tmp_path / "plain.npz"
    np.savez(plain, y=np.zeros(3))  # an npz without metadata
    for path, word in [(truncated, "corrupt or truncated"), (flipped, "corrupt"),
                       (empty, "corrupt or truncated"), (plain, "not a qsa file"),
                       (tmp_path / "missing.npz", "no such file")]:
        with pytest.raises(ValueError, match=word) as exc:
            load_npz(path)
        assert str(path) in str(exc.value)
