"""The status tables of the result types follow one convention (see the ``qsa`` docstring).

Each solver's tests check its results against its table with
``tests.helpers.assert_status_convention``; here the tables themselves are checked.
"""

import pytest

import qsa.continuation.branch
import qsa.equilibria.newton
import qsa.flows.solve
import qsa.reduction.integrate
import qsa.spectra.result

TABLES = {
    "PolishResult": qsa.equilibria.newton.MESSAGES,
    "Spectrum": qsa.spectra.result.MESSAGES,
    "Branch": qsa.continuation.branch.MESSAGES,
    "FrontODEResult": qsa.reduction.integrate.MESSAGES,
    "FlowResult": qsa.flows.solve.MESSAGES,
}


@pytest.mark.parametrize("name", sorted(TABLES))
def test_messages_table(name):
    table = TABLES[name]
    assert table[0] and all(isinstance(k, int) for k in table)
    assert any(k < 0 for k in table), "every solver can fail"
    assert all(isinstance(v, str) and v and v == v.strip() for v in table.values())
    # no message is the start of another (the status can be read back from a message)
    texts = list(table.values())
    assert not any(a != b and b.startswith(a) for a in texts for b in texts)


def test_old_polish_table_name_is_the_new_table():
    assert qsa.equilibria.newton.STATUS_MESSAGES is qsa.equilibria.newton.MESSAGES
