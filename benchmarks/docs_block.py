"""Write what a benchmark printed into a marked block of a docs/ page (``--update-docs``).

A block is the text between ``<!-- NAME:start -->`` and ``<!-- NAME:end -->`` on the
page; it is replaced as a whole, so prose belongs outside the markers.  The block
starts with one line naming the command and the load average at the start of the run.
"""

from __future__ import annotations

import contextlib
import io
import os
import shlex
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"


class _Tee(io.TextIOBase):
    """A text stream that writes to the terminal and keeps a copy."""

    def __init__(self, stream):
        self.stream = stream
        self.copy = io.StringIO()

    def write(self, text):
        self.stream.write(text)
        self.copy.write(text)
        return len(text)

    def flush(self):
        self.stream.flush()


def run_header(argv=None) -> str:
    """One line: the command as run (without ``--update-docs``), the load average, the core count."""
    argv = sys.argv if argv is None else argv
    script = Path(argv[0])
    if script.is_absolute():
        script = script.relative_to(DOCS.parent) if DOCS.parent in script.parents else Path(script.name)
    words = [str(script), *[word for word in argv[1:] if word != "--update-docs"]]
    return (f"`python {shlex.join(words)}`: load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
            "at the start.")


@contextlib.contextmanager
def captured_stdout():
    """Print as usual and keep a copy; the context value's ``.copy.getvalue()`` is the text printed."""
    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):
        yield tee


def write_block(page: str, name: str, body: str) -> None:
    """Replace the text between ``<!-- name:start -->`` and ``<!-- name:end -->`` in docs/``page`` by ``body``."""
    path = DOCS / page
    text = path.read_text(encoding="utf-8")
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    if text.count(start) != 1 or text.count(end) != 1:
        raise SystemExit(f"docs/{page} needs exactly one pair of markers {start} ... {end}")
    before, rest = text.split(start, 1)
    _old, after = rest.split(end, 1)
    path.write_text(f"{before}{start}\n{body.strip()}\n{end}{after}", encoding="utf-8")
    print(f"wrote docs/{page} block {name}", file=sys.stderr)


def run_and_write(main, page: str, name: str, update: bool, argv=None) -> None:
    """Run ``main()`` printing as usual; if ``update``, write the header and what it printed into the block."""
    header = run_header(argv)
    with captured_stdout() as tee:
        main()
    if update:
        write_block(page, name, header + "\n\n" + tee.copy.getvalue())


def repeats_main(argv, description: str, script: str, measure, page: str, name: str, repeats: int) -> None:
    """The command line of a benchmark with ``--repeats`` and ``--update-docs``: parse ``argv`` (None: the
    process's), run ``measure(args)`` and, with ``--update-docs``, write what it printed into block ``name``
    of docs/``page`` (``script``: the benchmark's path in the repository, for the block's header)."""
    import argparse

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--repeats", type=int, default=repeats)
    parser.add_argument("--update-docs", action="store_true",
                        help=f"also write the tables into docs/{page} (between its {name} markers)")
    args = parser.parse_args(argv)
    argv_used = None if argv is None else [script, *argv]
    run_and_write(lambda: measure(args), page, name, args.update_docs, argv_used)
