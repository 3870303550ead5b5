import numpy as np
import pytest

from qsa.resample import closed_samples, resample_closed
from tests.reference import load

CLOSED_FORMS = load("closed_forms")


def ellipse(M, a=1.0, b=2.0):
    t = 2 * np.pi * np.arange(M) / M
    return a * np.cos(t), b * np.sin(t)


def test_equal_arclength_and_chord():
    x, y = ellipse(64)
    for kind in ("fourier", "spline"):
        X, Y, L = resample_closed(x, y, 100, method="chord", interpolant=kind)
        ch = np.hypot(np.diff(np.append(X, X[0])), np.diff(np.append(Y, Y[0])))
        assert np.ptp(ch) < 1e-10 * ch.mean()
        assert (X[0], Y[0]) == pytest.approx((x[0], y[0]))
    _, _, L = resample_closed(x, y, 50, interpolant="fourier")
    assert abs(L - CLOSED_FORMS["ellipse_perimeter_a1_b2"]["value"]) < 1e-10


def test_repeated_endpoint_dropped():
    x, y = ellipse(32)
    x2, y2 = closed_samples(np.append(x, x[0]), np.append(y, y[0]))
    assert x2.size == 32


@pytest.mark.parametrize("case", ["nan", "open", "short", "dup", "shape"])
def test_bad_samples(case):
    x, y = ellipse(40)
    if case == "nan":
        x[3] = np.nan
    elif case == "open":
        x, y = x[:25], y[:25]
    elif case == "short":
        x, y = x[:3], y[:3]
    elif case == "dup":
        x[5], y[5] = x[4], y[4]
    elif case == "shape":
        y = y[:-1]
    with pytest.raises(ValueError):
        resample_closed(x, y, 32)


def test_equal_chord_large_N():
    """Sparse Newton: equal chords to round-off for thousands of points."""
    x, y = ellipse(300)
    X, Y, _ = resample_closed(x, y, 5000, method="chord")
    ch = np.hypot(np.diff(np.append(X, X[0])), np.diff(np.append(Y, Y[0])))
    assert np.ptp(ch) < 1e-10 * ch.mean()
