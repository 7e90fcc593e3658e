"""Command-line interface: ``wavecontact <command> ...``.

Each command lives in its own module exposing ``add_parser(subparsers)`` and
``run(args) -> int``.  Invalid input ends with a one-line message on stderr
and a non-zero exit status, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import WavecontactError

COMMANDS = ("collide", "converge", "ring", "equipartition", "compare", "gas", "map", "ensemble", "bath-figure",
            "restitution-table", "markov", "paper-figures")


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
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name.replace('-', '_')}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name.replace('-', '_')}":
                raise
            continue  # command not shipped yet
        module.add_parser(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from .._jit import announce_compilation

    try:
        with announce_compilation():  # a first run on an empty numba cache says why it is silent
            return int(args.run(args) or 0)
    except (WavecontactError, ValueError, OSError) as exc:
        print(f"wavecontact: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("wavecontact: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
