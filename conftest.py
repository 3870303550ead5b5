"""Collection settings of the test suite (tests/ and the doctests of qsa/)."""

try:
    import numba  # noqa: F401
except ImportError:  # the optional 'fast' extra: its compiled modules cannot be imported
    collect_ignore = ["qsa/reduction/_kernels.py", "qsa/reduction/_linalg.py"]
