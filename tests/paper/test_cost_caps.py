"""Cost caps on the appendix's example: an algorithmic regression fails a test, not a timer.

The run is the first row of the paper's time-step study (``qsa reproduce timesteps``):
the CHA convergence example at N = 100, local error tolerance 1e-3, backward Euler with
step doubling to physical time 0.2 (about a second).
"""

from qsa.paper.appendix import count_steps
from tests.reference import load

PAPER = load("paper_appendix")

#: Measured when the caps were set: 67 accepted passes, 1 rejected, 704 Newton
#: iterations, 44 LU factorizations (the caps are about 20% above).
CAPS = {"n_steps": 80, "n_rejected": 3, "n_newton": 845, "n_lu": 53}


def test_appendix_run_stays_within_its_cost_caps():
    tol = 1e-3
    run = count_steps([tol], N=100, t_final=0.2)[tol]
    counts = {name: getattr(run, name) for name in CAPS}
    assert all(counts[name] <= cap for name, cap in CAPS.items()), (counts, CAPS)
    # and the step count is the paper's (65) within 15%
    assert abs(run.n_steps / PAPER["time_steps"][tol] - 1) <= 0.15, run.n_steps
    # simplified Newton reuses its factorizations: far fewer LUs than Newton iterations
    assert run.n_lu < run.n_newton / 5
