"""Deprecated location of :mod:`qsa.continuation` (``continuation``, ``Branch``, ...).

Continuation stands above the equilibria and the spectra; import it from
``qsa.continuation``. This module re-exports those names and warns on import.
"""

from __future__ import annotations

import sys
import types
import warnings

from qsa.continuation import Branch, BranchPoint, Fold, continuation

__all__ = ["continuation", "Branch", "Fold", "BranchPoint"]

warnings.warn("qsa.equilibria.continuation is deprecated; import continuation, Branch, "
              "BranchPoint and Fold from qsa.continuation", DeprecationWarning, stacklevel=2)


class _CallableModule(types.ModuleType):
    """This module, callable as :func:`qsa.continuation.continuation`.

    Importing ``qsa.equilibria.continuation`` binds the module object to the package
    attribute of the same name, which used to be the function; calling it keeps working.
    """

    def __call__(self, *args, **kwargs):
        return continuation(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
