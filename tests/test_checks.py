"""The argument checkers: values accepted, and one-line messages naming the argument."""

import numpy as np
import pytest

from qsa._checks import finite_array, integer, real_number


@pytest.mark.parametrize("value, kw, expected", [
    ("0.5", {}, 0.5), (np.float32(2), {"positive": True}, 2.0), (0, {"nonnegative": True}, 0.0),
    (np.inf, {"allow_inf": True, "positive": True}, np.inf), (-3, {}, -3.0),
])
def test_real_number_accepts(value, kw, expected):
    assert real_number(value, "x", **kw) == expected


@pytest.mark.parametrize("value, kw, match", [
    ("a", {}, "x must be a number, got 'a'"),
    (None, {"positive": True}, "x must be a positive number, got None"),
    (np.nan, {"allow_inf": True}, "x must be a finite number, got nan"),
    (np.inf, {"positive": True}, "x must be a positive finite number, got inf"),
    (0.0, {"positive": True}, "x must be positive, got 0.0"),
    (-1e-300, {"nonnegative": True}, "x must be non-negative, got -1e-300"),
])
def test_real_number_rejects(value, kw, match):
    with pytest.raises(ValueError, match=match):
        real_number(value, "x", **kw)


def test_integer():
    assert integer(np.int32(7), "n", minimum=7) == 7 and type(integer(np.int64(3), "n")) is int
    for bad in (True, np.bool_(False), 3.0, "3", None):
        with pytest.raises(ValueError, match=r"^n must be an integer >= 2, got "):
            integer(bad, "n", minimum=2)
    with pytest.raises(ValueError, match=r"^n=1: need n >= 2$"):
        integer(1, "n", minimum=2)
    with pytest.raises(ValueError, match=r"^N=3 is too small: need N >= 8$"):
        integer(3, "N", minimum=8,
                too_small="{name}={value} is too small: need {name} >= {minimum}")
    with pytest.raises(ValueError, match=r"^N must be an integer number of nodes, got 'x'$"):
        integer("x", "N", what="number of nodes")


def test_finite_array():
    a = finite_array([[1, 2], [3, 4]], "U", shape=(None, 2))
    assert a.dtype == float and a.shape == (2, 2)
    with pytest.raises(ValueError, match=r"U has shape \(2, 2\), expected \(n, 3\)"):
        finite_array(a, "U", shape=(None, 3))
    with pytest.raises(ValueError, match=r"U has shape \(2, 2\), expected \(4,\)"):
        finite_array(a, "U", shape=(4,))
    with pytest.raises(ValueError, match="U must be finite; it contains NaN or inf"):
        finite_array([1.0, np.inf], "U")
    with pytest.raises(ValueError, match="U must be an array of real numbers"):
        finite_array(["a", 1.0], "U")


@pytest.mark.parametrize("call, match", [
    (lambda: __import__("qsa").Fourier(5), "N=5 is too small for a Fourier grid: need N >= 8"),
    (lambda: __import__("qsa").FiniteDifference(8.0), "N must be an integer number of nodes"),
])
def test_grid_messages_kept(call, match):
    with pytest.raises(ValueError, match=match):
        call()
