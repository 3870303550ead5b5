"""Exit codes and the error handling every ``qsa`` subcommand shares.

:func:`qsa.cli.main` runs each subcommand's ``run(args)`` through
:func:`run_command`, so a subcommand only raises or returns; it never prints a
traceback, and the same failure gives the same exit code in every subcommand:

=====  ==================================================================
code   meaning
=====  ==================================================================
0      done
1      the computation ran and reports a failure (``success = False``: a
       solver that did not converge, a flow stopped early); its message is
       printed and its last good state kept
2      bad input, refused with one line on stderr naming the argument or
       file: an invalid value, a missing or unreadable input file, an output
       that cannot be written (checked before the work starts), a run that
       would need more memory than is available
130    interrupted (Ctrl-C); a flow first saves its checkpoint and prints how
       to continue from it with ``--resume``
141    the reader of the output went away (e.g. ``qsa ... | head``): exits
       quietly, as a program killed by SIGPIPE does
=====  ==================================================================

Warnings (a value the command changed, an option it ignored) are one line on
stderr starting ``qsa <command>: warning:``; they do not change the exit code.
"""

from __future__ import annotations

import os
import sys
import textwrap

__all__ = ["EXIT_OK", "EXIT_FAILURE", "EXIT_BAD_INPUT", "EXIT_INTERNAL", "EXIT_INTERRUPTED",
           "EXIT_BROKEN_PIPE", "EXIT_CODES", "epilog", "run_command", "warn", "note",
           "silence_stdout"]

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141

#: One line per exit code, as ``qsa --help`` lists them.
EXIT_CODES = {
    EXIT_OK: "done",
    EXIT_FAILURE: "the computation ran and reports a failure (solver not converged, flow "
                  "stopped early): message printed, last good state kept",
    EXIT_BAD_INPUT: "bad input, one line on stderr: invalid value, unreadable input file, "
                    "output that cannot be written (checked before any work), not enough "
                    "memory for the run",
    EXIT_INTERNAL: "an internal error (a bug in qsa): one line on stderr naming it; "
                   "QSA_TRACEBACK=1 in the environment shows the traceback",
    EXIT_INTERRUPTED: "interrupted (Ctrl-C); a flow saves its checkpoint and prints the "
                      "--resume that continues it",
    EXIT_BROKEN_PIPE: "the output pipe was closed (e.g. | head): quiet exit",
}


def epilog() -> str:
    """The exit-code table of ``qsa --help``.

    Returns
    -------
    str

    Examples
    --------
    >>> print(epilog().splitlines()[1])
        0  done
    """
    lines = ["exit codes:"]
    for code, text in EXIT_CODES.items():
        lines += textwrap.wrap(text, 79, initial_indent=f"  {code:>3}  ",
                               subsequent_indent=" " * 7)
    return "\n".join(lines)


def warn(args, message) -> None:
    """Print ``<prog>: warning: <message>`` on stderr (a value changed, an option ignored).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (their ``qsa_prog`` names the subcommand).
    message : str
        One line: what was changed and to what.
    """
    print(f"{_prog(args)}: warning: {message}", file=sys.stderr, flush=True)


def note(args, message) -> None:
    """Print ``<prog>: <message>`` on stderr (what a long step is doing before it starts)."""
    print(f"{_prog(args)}: {message}", file=sys.stderr, flush=True)


def _prog(args):
    return getattr(args, "qsa_prog", None) or "qsa"


def _error(args, message):
    print(f"{_prog(args)}: error: {message}", file=sys.stderr, flush=True)


def _oserror_text(exc):
    name = exc.filename if exc.filename is not None else ""
    what = exc.strerror or str(exc)
    return f"{name}: {what}" if name else what


def silence_stdout():
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # stdout already closed or not a file
        pass


def run_command(func, args) -> int:
    """Run ``func(args)`` and turn what it raises into a message and an exit code.

    Parameters
    ----------
    func : callable
        A subcommand's ``run(args) -> int``.
    args : argparse.Namespace

    Returns
    -------
    int
        ``func``'s own code (0 or 1), or 2 (``ValueError``, ``OSError``,
        ``MemoryError``), 130 (``KeyboardInterrupt``; a
        :class:`qsa.flows.FlowInterrupted` adds its checkpoint), 141
        (``BrokenPipeError``) or 70 (any other exception: a bug, reported in one line
        unless ``QSA_TRACEBACK`` is set, when it is raised).
    """
    try:
        code = int(func(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        silence_stdout()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt as exc:
        checkpoint = getattr(exc, "checkpoint", None)
        if checkpoint:
            hint = getattr(args, "resume_hint", None)
            how = hint(args, checkpoint) if hint else \
                f"the same command and --resume {checkpoint}"
            t = getattr(exc, "t", None)
            at = "" if t is None else f" at t = {t:.6g}"
            _error(args, f"interrupted{at}; checkpoint saved in {checkpoint}; continue with: "
                         f"{how}")
        else:
            hint = getattr(args, "interrupt_hint", None)
            _error(args, "interrupted" + (f"; {hint(args)}" if hint else ""))
        return EXIT_INTERRUPTED
    except MemoryError as exc:
        detail = f" ({exc})" if str(exc) else ""
        _error(args, f"out of memory{detail}")
        return EXIT_BAD_INPUT
    except ValueError as exc:
        _error(args, str(exc))
        return EXIT_BAD_INPUT
    except OSError as exc:
        _error(args, _oserror_text(exc))
        return EXIT_BAD_INPUT
    except Exception as exc:
        if os.environ.get("QSA_TRACEBACK"):
            raise
        where = exc.__traceback__
        while where is not None and where.tb_next is not None:
            where = where.tb_next
        at = "" if where is None else \
            f" at {os.path.basename(where.tb_frame.f_code.co_filename)}:{where.tb_lineno}"
        _error(args, f"internal error: {type(exc).__name__}: {exc}{at} (a bug in qsa; "
                     "QSA_TRACEBACK=1 shows the traceback)")
        return EXIT_INTERNAL
