"""The command line's parser, option types and path checks, shared by every subcommand.

* :class:`CommandParser` -- ``argparse.ArgumentParser`` that reads negative numbers
  in exponent form (``--tol -1e-4`` reaches the option, which then rejects it),
  reports a usage error in one line, and records its ``prog`` for messages.
* Option types (:func:`positive_float`, :func:`positive_int`, ...): a bad value is
  refused by argparse with the option's name (exit code 2).
* :func:`check_paths` -- run by :func:`qsa.cli.main` before a subcommand starts:
  input files (``--init``, ``--resume FILE``, ``--from``) must exist, output folders (``--out``)
  and files (``--plot``, ``--save``, ``--checkpoint``) must be writable, so that a
  long run is not lost at its end to a typo in an output path.

Examples
--------
>>> p = CommandParser(prog="qsa demo")
>>> _ = p.add_argument("--tol", type=positive_float)
>>> p.parse_args(["--tol", "1e-4"]).tol
0.0001
>>> positive_float("-1e-4")
Traceback (most recent call last):
...
argparse.ArgumentTypeError: must be a positive number, got -1e-4
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import tempfile

__all__ = ["CommandParser", "positive_float", "nonnegative_float", "finite_float",
           "positive_int", "int_at_least", "check_paths", "FIGURE_FORMATS"]

#: Extensions ``--plot`` can write (matplotlib's formats).
FIGURE_FORMATS = ("png", "pdf", "svg", "svgz", "eps", "ps", "jpg", "jpeg", "tif", "tiff",
                  "webp", "pgf", "raw", "rgba")

#: Options naming an output folder, an output file, an input file (by ``dest``).
OUTPUT_FOLDERS = ("out",)
OUTPUT_FILES = ("plot", "save", "checkpoint", "movie")
INPUT_FILES = ("init", "resume", "from")

# -1, -.5, -1e-4, -2.5E+3, -inf, -nan: arguments, not options (argparse's own pattern
# misses the exponent form)
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$|^-(inf|nan)$", re.I)


class CommandParser(argparse.ArgumentParser):
    """``ArgumentParser`` for ``qsa``: negative numbers in any form, one-line errors.

    Its sub-parsers are of the same class (``add_subparsers`` uses the parent's
    class), and each records its ``prog`` as the default ``qsa_prog``, so the
    innermost one (``qsa flow cha``) names the command in messages.
    """

    def __init__(self, *args, **kwargs):
        if kwargs.get("epilog") is None:
            kwargs["epilog"] = ("exit codes: 0 done, 1 failure reported, 2 bad input, "
                                "70 internal error, 130 interrupted (see qsa --help)")
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER
        self.set_defaults(qsa_prog=self.prog)

    def error(self, message):
        """Print ``<prog>: error: <message>`` (and where to find the usage); exit 2."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def finite_float(text) -> float:
    """A finite float (``nan`` and ``inf`` refused)."""
    v = _number(text)
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return v


def positive_float(text) -> float:
    """A finite float ``> 0``."""
    v = _number(text)
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return v


def nonnegative_float(text) -> float:
    """A finite float ``>= 0``."""
    v = _number(text)
    if not (math.isfinite(v) and v >= 0):
        raise argparse.ArgumentTypeError(f"must be a non-negative number, got {text}")
    return v


def int_at_least(minimum):
    """Type: an integer ``>= minimum`` (``"1e3"`` and ``"2.5"`` are refused, not truncated)."""

    def parse(text):
        try:
            v = int(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if v < minimum:
            raise argparse.ArgumentTypeError(f"must be an integer >= {minimum}, got {text}")
        return v

    parse.__name__ = f"integer >= {minimum}"
    return parse


positive_int = int_at_least(1)


# ------------------------------------------------------------------ paths
def _flag(dest):
    return "--" + dest.replace("_", "-")


def _probe_folder(folder, flag, value):
    """Create ``folder`` if needed and write (and remove) a file in it."""
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise ValueError(f"{flag} {value}: is a file, not a folder")
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise ValueError(f"{flag} {value}: cannot write in {folder} "
                         f"({exc.strerror or exc})") from None


def check_output_folder(path, flag="--out"):
    """Refuse an output folder that is a file or cannot be created or written.

    Parameters
    ----------
    path : str
        The folder (created if missing, as the command would create it).
    flag : str
        The option, for the message.

    Raises
    ------
    ValueError
    """
    _probe_folder(os.path.abspath(path), flag, path)


def check_output_file(path, flag):
    """Refuse an output file that is a folder or lies in a missing or read-only folder.

    ``--plot`` also needs a figure format it can write (``.png``, ``.pdf``, ...).

    Returns
    -------
    str
        The path to write (``--plot`` without an extension gets ``.png``, which
        matplotlib would otherwise add silently).
    """
    if os.path.isdir(path):
        example = os.path.join(path, "figure.png" if flag == "--plot" else "result.npz")
        raise ValueError(f"{flag} {path}: is a folder; give a file name, e.g. {example}")
    if flag == "--plot":
        ext = os.path.splitext(path)[1].lstrip(".").lower()
        if not ext:
            path = path + ".png"
        elif ext not in FIGURE_FORMATS:
            raise ValueError(f"{flag} {path}: unknown figure format .{ext}; use one of "
                             + ", ".join("." + f for f in FIGURE_FORMATS[:6]))
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"{flag} {path}: the folder {os.path.dirname(path) or folder} "
                         "does not exist")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise ValueError(f"{flag} {path}: the file is not writable")
    _probe_folder(folder, flag, path)
    return path


def check_input_file(path, flag):
    """Refuse an input file that is missing, a folder, or unreadable."""
    if not os.path.exists(path):
        raise ValueError(f"{flag} {path}: no such file")
    if os.path.isdir(path):
        raise ValueError(f"{flag} {path}: is a folder, not a file")
    if not os.access(path, os.R_OK):
        raise ValueError(f"{flag} {path}: the file is not readable")


def check_paths(args) -> None:
    """Check every path option of a parsed command line before the work starts.

    Looks at the options named (by ``dest``) in :data:`INPUT_FILES`,
    :data:`OUTPUT_FOLDERS` and :data:`OUTPUT_FILES` that hold a string; ``--plot``
    without an extension is completed to ``.png`` in ``args``.

    Raises
    ------
    ValueError
        One line naming the option, the path and the problem.
    """
    for dest in INPUT_FILES:
        value = getattr(args, dest, None)
        if isinstance(value, str):
            check_input_file(value, _flag(dest))
    for dest in OUTPUT_FOLDERS:
        value = getattr(args, dest, None)
        if isinstance(value, str):
            check_output_folder(value, _flag(dest))
    for dest in OUTPUT_FILES:
        value = getattr(args, dest, None)
        if isinstance(value, str):
            setattr(args, dest, check_output_file(value, _flag(dest)))


def stderr_is_terminal() -> bool:
    """Whether progress bars should be drawn (only on a terminal)."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False
