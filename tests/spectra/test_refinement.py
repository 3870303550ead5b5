"""Refined solves with a bordered system (qsa.spectra.refinement): residual precisions, probe."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from qsa.linalg import BlockSparse
from qsa.spectra.refinement import BorderedSystem, column_norms, probe, refined_solve


def _unbordered(core):
    n = core.shape[0]
    return BorderedSystem(core, np.zeros((n, 0)), np.zeros((0, n)), np.zeros((0, 0)))


@pytest.mark.skipif(np.finfo(np.longdouble).nmant < 62, reason="no extended precision")
def test_residual_precisions_working_mixed_extended():
    # row 0 = x0 + x1 + (sum of the 20 entries of a wide block); x1 and x3 are 2^-60
    one = lambda m, n: sp.csr_matrix(np.ones((m, n)))
    core = BlockSparse([[one(1, 1), one(1, 1), one(1, 20)],
                        [one(1, 1), None, None],
                        [None, None, sp.identity(20, format="csr")]])
    system = _unbordered(core)
    assert system.wide is not None and system.wide.tolist() == [[False, False, True],
                                                                 [False, False, False],
                                                                 [False, False, False]]
    x = np.zeros(22)
    x[[0, 2]] = 1.0
    x[[1, 3]] = 2.0**-60
    rhs = core @ x  # row 0 rounds to 2
    assert rhs[0] == 2.0
    assert system.residual(rhs, x, 0)[0] == 0.0                        # working: rounded
    assert system.residual(rhs, x, 0, "mixed")[0] == -(2.0**-60)      # the wide block rounded
    assert system.residual(rhs, x, 0, "extended")[0] == -(2.0**-59)   # exact
    # a dense core has no wide blocks: mixed is extended
    dense = _unbordered(core.tocsr().toarray())
    assert dense.wide is None
    assert dense.residual(rhs, x, 0, "mixed")[0] == -(2.0**-59)


def test_probe_flags_a_nearly_singular_system_and_the_estimate_covers_the_error():
    mpmath = pytest.importorskip("mpmath")
    n = 10
    w = np.full(n, 1.0 / n)
    well = np.eye(n) + 0.1 * np.random.default_rng(0).standard_normal((n, n))
    hilbert = sla.hilbert(n)  # cond ~ 1.6e13: working-precision refinement stalls
    found = {}
    for name, A in (("well", well), ("hilbert", hilbert)):
        lu = sla.lu_factor(A)
        solve = lambda b, lu=lu: sla.lu_solve(lu, b)
        system = _unbordered(A)
        found[name] = probe(solve, system, 0, w)
        b = np.arange(1.0, n + 1)
        x, dx, noise = refined_solve(solve, system, 0, b, 1, found[name], w, estimate=True)
        with mpmath.workdps(50):
            exact = mpmath.lu_solve(mpmath.matrix(A.tolist()), mpmath.matrix(b.tolist()))
            err = np.array([float(x[i] - exact[i]) for i in range(n)])
        estimate = column_norms(dx, w) + noise * column_norms(x, w)
        assert column_norms(err, w) <= 2 * estimate
    assert not found["well"].extended and found["well"].noise == 0.0  # dense: no wide blocks
    assert found["hilbert"].extended
