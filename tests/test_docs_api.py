"""The API reference (docs/api.md) lists every public name, under the module that exports it."""

import importlib
import pkgutil
import re
from pathlib import Path

import qsa

API = Path(__file__).resolve().parent.parent / "docs" / "api.md"


def sections():
    """``{module: set of names}`` as listed in the autosummary blocks of docs/api.md."""
    out = {}
    module = None
    for line in API.read_text().splitlines():
        head = re.fullmatch(r"## `([\w.]+)`", line)
        if head:
            module = head.group(1)
            out[module] = set()
        elif module and re.fullmatch(r"   ~?[\w.]+", line):
            out[module].add(line.strip().rsplit(".", 1)[-1].lstrip("~"))
    return out


def public_packages():
    """Every public subpackage of qsa (no leading underscore, not the command line)."""
    names = ["qsa"]
    for info in pkgutil.walk_packages(qsa.__path__, "qsa."):
        parts = info.name.split(".")
        if info.ispkg and not any(p.startswith("_") for p in parts) and parts[1] != "commands":
            names.append(info.name)
    return names


def test_every_listed_module_is_complete():
    listed = sections()
    assert len(listed) >= 20
    for module, names in listed.items():
        exported = set(importlib.import_module(module).__all__)
        assert names == exported, (module, exported - names, names - exported)


def test_every_public_package_is_listed():
    listed = sections()
    missing = [name for name in public_packages() if name not in listed]
    assert not missing, missing
