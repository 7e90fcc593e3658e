"""Command-line interface: ``wavecontact <command> ...``.

Each command lives in its own module exposing ``add_parser(subparsers)`` and
``run(args) -> int``.  Invalid input ends with a one-line message on stderr
and a non-zero exit status, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from ..errors import WavecontactError

COMMANDS = ("collide", "converge", "ring", "equipartition", "compare", "gas", "map", "ensemble", "bath-figure",
            "restitution-table", "markov", "paper-figures", "solve")


class _Parser(argparse.ArgumentParser):
    """One-line errors; every command's help states its options' defaults (``common.HelpFormatter``)."""

    def __init__(self, *args, **kwargs):
        from .common import HelpFormatter

        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):  # one line, exit status 2, as argparse does
        self.exit(2, f"wavecontact: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from .._version import __version__
    parser = _Parser(prog="wavecontact", description="Collisions of elastic rods and their restitution.")
    parser.add_argument("--version", action="version", version=f"wavecontact {__version__}",
                        help="print the version and exit")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")
    for name in COMMANDS:  # every command ships: a missing module is an error, not a command left out
        importlib.import_module(f"{__name__}.{name.replace('-', '_')}").add_parser(sub)
    return parser


def _say(message: str) -> None:
    print(f"wavecontact: {' '.join(str(message).split())}", file=sys.stderr)


def _interrupted_kernel(exc: BaseException) -> bool:
    """Ctrl-C inside a numba kernel surfaces as ``SystemError: ... returned a result with an exception set``
    whose cause is the KeyboardInterrupt."""
    seen = exc
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return True
        seen = seen.__cause__ or seen.__context__
    return isinstance(exc, SystemError) and "returned a result with an exception set" in str(exc)


def _stopped() -> int:
    from .executors import lost_cluster

    reason = lost_cluster()
    if reason is not None:
        _say(f"error: {reason}")
        return 2
    _say("interrupted")
    return 130


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone (poll reports an error on its end)."""
    try:
        import select

        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(events & select.POLLERR for _, events in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows) or no descriptor: trust the exception
        return True


def _reader_gone() -> int:
    """The reader of standard output closed it (``| head``): stop quietly, as a command killed by SIGPIPE.

    Standard output is pointed at the null device so that the interpreter's flush at exit does not
    raise again; the status is 141, the shell's for a command ended by SIGPIPE.
    """
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # no file descriptor behind sys.stdout (an embedding application)
        pass
    return 141


def _cancelled(exc: BaseException) -> bool:
    """A Dask future cancelled or a connection closed: the scheduler or the workers went away."""
    import asyncio
    import concurrent.futures

    if isinstance(exc, (concurrent.futures.CancelledError, asyncio.CancelledError)):
        return True
    return type(exc).__module__.startswith("distributed")


def main(argv=None) -> int:
    """Run one command; every failure ends with one line on stderr and a non-zero status.

    Exit status 0 success, 2 refused or failed (the line says why), 130 interrupted (Ctrl-C), 141 when
    the reader of its standard output went away first (``wavecontact ... | head``; nothing is printed).
    """
    from concurrent.futures.process import BrokenProcessPool

    from .._jit import announce_compilation

    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        with announce_compilation():  # a first run on an empty numba cache says why it is silent
            status = int(args.run(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's own flush at exit
        return status
    except BrokenPipeError as exc:
        if _stdout_closed():
            return _reader_gone()
        _say(f"error: {exc}")  # another pipe (a worker's): a failure like any other
        return 2
    except KeyboardInterrupt:
        return _stopped()
    except MemoryError:
        _say("error: out of memory; run a smaller case (fewer samples, collisions or modes)")
        return 2
    except BrokenProcessPool:
        _say("error: a worker process died (killed or out of memory); the run was stopped")
        return 2
    except (WavecontactError, ValueError, OSError, argparse.ArgumentTypeError) as exc:
        if _interrupted_kernel(exc):
            return _stopped()
        _say(f"error: {exc}")
        return 2
    except BaseException as exc:  # SystemExit passes; anything else is a failure to report in one line
        if isinstance(exc, SystemExit):
            raise
        if _interrupted_kernel(exc):
            return _stopped()
        if _cancelled(exc):
            from .executors import lost_cluster

            _say(f"error: {lost_cluster() or 'the Dask scheduler or its workers were lost'} ({type(exc).__name__})")
            return 2
        raise


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
