"""The command line every example shares: ``python examples/NAME.py [--out DIR]``.

Examples write their figures and files into ``--out`` (default ``examples_output/``, which
.gitignore covers), never into the current directory itself.
"""

import argparse

DEFAULT = "examples_output"


def output_folder(doc: str) -> str:
    """The folder given by ``--out`` on the command line (the example creates it); ``doc``'s first
    paragraph is the help's description."""
    parser = argparse.ArgumentParser(description=" ".join(doc.strip().split("\n\n")[0].split()))
    parser.add_argument("--out", default=DEFAULT, metavar="DIR",
                        help=f"folder for the figures and files the example writes (default: {DEFAULT}/)")
    return parser.parse_args().out
