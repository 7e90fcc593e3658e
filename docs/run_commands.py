"""Run every command shown in README.md and docs/, as a fresh user following the pages would.

    python docs/run_commands.py            # the cheap commands (tests/test_docs.py runs them too)
    python docs/run_commands.py --all      # every command that can run here (tens of minutes on 2 cores)
    python docs/run_commands.py --list     # every command shown, its page and its class

A command is a line of a code block (fenced or indented) that starts with ``wavecontact``,
``python`` or ``pip`` (``&&`` splits a line into commands; a synopsis with ``[...]``, ``...``,
``|`` or ``<placeholder>`` is not a command). Classes:

* ``cheap``: listed in :data:`CHEAP` (seconds each), and every ``--help`` and ``--version``;
* ``example``: ``python examples/...``, run by tests/test_examples.py (``--all`` runs them here too);
* ``not run``: installing the package or running the test suite itself (:data:`NOT_RUN` says why);
* ``expensive``: every other command, run by ``--all``.

Each command runs in a new empty directory, with this checkout first on ``PYTHONPATH`` (files it
writes land there, not in the repository; directories of the checkout that the command names, such
as ``docs/figures/examples``, are created there first, as a user in the checkout would have them). It passes when it ends with status 0 and every path
named after ``--out``, ``--plot``, ``--xt-plot``, ``--fields`` or ``--page`` exists afterwards.
What the commands print is compared with the pages by ``python docs/generate.py --check`` (the
generated blocks), not here.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

CHEAP = {
    "wavecontact collide --gamma 0.6 --kappa 100",
    "wavecontact collide --gamma 0.6 --kappa 100 --json",
    "wavecontact collide --gamma 0.6 --kappa 5 --plot w.png",
    "wavecontact collide --gamma 0.6 --kappa inf",
    "wavecontact collide --solver fem --gamma 0.6 --kappa 100 --elements 800 --xt-plot xt.png --fields out/",
    "wavecontact converge --gamma 0.6 --kappa 20 --order 1 2 --mass lumped consistent --elements 25 50 100 200",
    ("wavecontact markov --gamma 0.6 --rule glauber --bath conserved --modes-per-rod 10 --initial-energy 21 "
    "--steps 40 --chains 400"),
}
NOT_RUN = {
    r"^pip install": "installs the package (this checkout is already installed)",
    r"^python -m pytest": "the test suite itself",
    r"--update-docs": "rewrites a block of a page in docs/ (run it by hand to refresh that page)",
    r"^python -m sphinx": "builds the documentation site from this checkout (tests/test_docs_site.py, marked slow)",
}
PATH_OPTIONS = ("--out", "--plot", "--xt-plot", "--fields", "--page")
SYNOPSIS = re.compile(r"\[|\.\.\.|\||<\w")
STARTS = re.compile(r"^(wavecontact|python|pip) ")


def shown_commands():
    """``[(page name, command)]`` of every command in a code block of the pages, in page order, once each."""
    seen, out = set(), []
    for page in PAGES:
        fenced, lines = False, []
        for line in page.read_text().splitlines():
            if line.startswith("```"):
                fenced = not fenced
                continue
            if fenced or line.startswith("    "):
                lines.append(line)
        joined = re.sub(r"\\\n\s*", " ", "\n".join(lines))
        for line in joined.splitlines():
            line = line.strip().removeprefix("$ ").strip()
            for command in line.split("&&"):
                command = re.split(r"\s#", command)[0].strip()  # a comment after the command
                if STARTS.match(command) and not SYNOPSIS.search(command) and command not in seen:
                    seen.add(command)
                    out.append((page.name, command))
    return out


def classify(command: str) -> str:
    """``cheap``, ``example``, ``not run`` or ``expensive``."""
    if command in CHEAP or re.search(r"^wavecontact( [\w-]+)? --(help|version)$", command):
        return "cheap"
    if any(re.search(pattern, command) for pattern in NOT_RUN):
        return "not run"
    if command.startswith("python examples/"):
        return "example"
    return "expensive"


def argv_of(command: str) -> list:
    """The process to start for ``command`` (scripts of this checkout by absolute path)."""
    words = shlex.split(command)
    if words[0] == "wavecontact":
        return [sys.executable, "-m", "wavecontact", *words[1:]]
    if words[:2] == ["python", "-m"] and words[2].split(".")[0] == "wavecontact":
        return [sys.executable, *words[1:]]
    if words[0] == "python" and words[1].endswith(".py"):
        return [sys.executable, str(ROOT / words[1]), *words[2:]]
    raise ValueError(f"cannot run {command!r}")


def written_paths(command: str) -> list:
    """The paths a command names as its outputs (after ``--out``, ``--plot``, ...)."""
    words = shlex.split(command)
    paths = []
    for i, word in enumerate(words[:-1]):
        if word in PATH_OPTIONS:
            for value in words[i + 1:]:
                if value.startswith("-"):
                    break
                paths.append(value)
    return paths


def prepare_scratch(command: str, scratch) -> None:
    """Make the directories of the checkout that ``command`` names (as arguments) in the empty directory ``scratch``."""
    for word in shlex.split(command)[1:]:
        if not word.startswith("-") and (ROOT / word).is_dir() and not Path(word).is_absolute():
            (Path(scratch) / word).mkdir(parents=True, exist_ok=True)


def missing_outputs(command: str, scratch) -> list:
    """The output paths of ``command`` (:func:`written_paths`) that are not in ``scratch`` after it ran."""
    return [p for p in written_paths(command) if not (Path(scratch) / p).exists()]


def run(command: str, timeout: float = 3600.0) -> tuple:
    """Run one command in an empty directory; ``(ok, seconds, message)``."""
    with tempfile.TemporaryDirectory() as scratch:
        prepare_scratch(command, scratch)
        environment = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "COLUMNS": "100"}
        start = time.perf_counter()
        try:
            done = subprocess.run(argv_of(command), cwd=scratch, env=environment, capture_output=True, text=True,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            return False, time.perf_counter() - start, f"no result within {timeout:.0f} s"
        seconds = time.perf_counter() - start
        if done.returncode != 0:
            return False, seconds, f"exit status {done.returncode}: {done.stderr.strip()[-1500:]}"
        missing = missing_outputs(command, scratch)
        if missing:
            return False, seconds, f"did not write {', '.join(missing)}"
        return True, seconds, ""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--all", action="store_true", help="run the expensive commands and the examples too")
    parser.add_argument("--list", action="store_true", help="list the commands and their class, run nothing")
    args = parser.parse_args(argv)
    commands = shown_commands()
    if args.list:
        for page, command in commands:
            kind = classify(command)
            reason = next((why for pattern, why in NOT_RUN.items() if re.search(pattern, command)), "")
            print(f"{kind:9s} {page:18s} {command}" + (f"   ({reason})" if reason else ""))
        return 0
    wanted = ("cheap", "expensive", "example") if args.all else ("cheap",)
    failed = 0
    for page, command in commands:
        if classify(command) not in wanted:
            continue
        ok, seconds, message = run(command)
        failed += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {seconds:7.1f} s  {page}: {command}" + ("" if ok else f"\n     {message}"),
              flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    try:
        status = main()
        sys.stdout.flush()
    except BrokenPipeError:  # `--list | head`: the reader stopped early; end quietly, as a command killed by SIGPIPE
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = 141
    sys.exit(status)
