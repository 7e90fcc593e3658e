"""Every command line of README.md's ``bash`` blocks runs as written, at small sizes.

A line is split at ``&&`` and a trailing ``# comment`` is dropped. Commands that install the package or
run a test suite are not run here (:data:`NOT_RUN` says why); every other one runs in its own empty
directory with this checkout first on ``PYTHONPATH``, after the substitutions of :data:`SMALL` (the
same command with fewer collisions, samples or grid points, so that the whole README runs in minutes),
and must end with status 0 having written the files it names after ``--out``, ``--plot``, ...

The fast test checks that every README command is either run or listed as not run, that every
substitution is still used, and that each substituted command parses; the slow one runs them.
What the commands print is compared with the pages elsewhere (``python docs/generate.py --check``).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from wavecontact.cli import build_parser

ROOT = Path(__file__).resolve().parent.parent

# (pattern, replacement, what it shrinks): applied in this order to each command that is run
SMALL = [
    (r"--elements 800\b", "--elements 100", "FE mesh of the x-t plot and the fields"),
    (r"--collisions 4500\b", "--collisions 30", "ring: collisions"),
    (r"--modes 10 20 40 75\b", "--modes 10 20 --collisions 20 --realisations 2", "equipartition: N, collisions, runs"),
    (r"--steps 10000\b", "--steps 100", "markov: collisions per chain"),
    (r"--samples 2000\b", "--samples 16", "ensemble, restitution-table: samples"),
    (r"^(wavecontact bath-figure \d+)", r"\1 --samples 8 --bath-modes 20", "bath figure: samples and modes"),
    (r"--rods 500 --collisions 100000\b", "--rods 20 --collisions 400", "gas: rods and collisions"),
    (r"^(wavecontact map .*)--out", r"\1--impedance-ratio 0.5:2:3 --time-ratio 0.5:2:3 --out", "map: 3 x 3 grid"),
    (r"^(wavecontact paper-figures)", r"\1 --quick --only 5", "paper figures: one figure, quick sizes"),
    (r"^(wavecontact compare .*)$", r"\1 --repeats 1", "compare: one timing per method"),
    (r"(wavecontact solve )examples/", r"\1" + str(ROOT / "examples") + "/", "scene files: read from the checkout"),
    (r"(hammer_on_bar.toml)", r"\1 --elements 50", "scene file: mesh"),
]
NOT_RUN = {
    r"^pip install": "installs the package; this test runs the checkout itself",
    r"^python -m pytest": "the test suite itself",
    r"^python -m sphinx": "builds the documentation site: tests/test_docs_site.py (slow)",
}
PATH_OPTIONS = ("--out", "--plot", "--xt-plot", "--fields", "--page")


def readme_commands(text: str | None = None) -> list[str]:
    """The commands of README.md's ``bash`` blocks, in order."""
    text = (ROOT / "README.md").read_text() if text is None else text
    commands = []
    for block in re.findall(r"^```bash\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL):
        for line in block.splitlines():
            for command in line.split("&&"):
                command = re.split(r"\s#", command)[0].strip()
                if command:
                    commands.append(command)
    return commands


def not_run(command: str) -> str | None:
    return next((why for pattern, why in NOT_RUN.items() if re.search(pattern, command)), None)


def small(command: str) -> str:
    for pattern, replacement, _ in SMALL:
        command = re.sub(pattern, replacement, command)
    return command


RUN = [c for c in readme_commands() if not not_run(c)]


def test_the_readme_has_commands_and_all_of_them_are_run_or_said_why_not():
    commands = readme_commands()
    assert len(RUN) >= 15, RUN
    for command in commands:
        assert not_run(command) or command.startswith("wavecontact "), f"README: no rule runs {command!r}"


def test_extraction_splits_chains_and_drops_comments():
    text = "x\n```bash\npip install . && wavecontact collide --gamma 1 --kappa 2   # a comment\n```\n" \
           "```text\nwavecontact not-a-command\n```\n"
    assert readme_commands(text) == ["pip install .", "wavecontact collide --gamma 1 --kappa 2"]


def test_every_substitution_is_used_and_every_command_parses():
    used = {pattern for pattern, _, _ in SMALL if any(re.search(pattern, c) for c in RUN)}
    assert used == {pattern for pattern, _, _ in SMALL}, "a substitution no README command needs: remove it"
    parser = build_parser()
    for command in RUN:
        for line in (command, small(command)):
            try:
                parser.parse_args(shlex.split(line)[1:])
            except SystemExit as stop:
                pytest.fail(f"README command does not parse ({stop.code}): {line}")


@pytest.mark.slow
@pytest.mark.parametrize("command", RUN)
def test_readme_command_runs(command, tmp_path):
    line = small(command)
    words = shlex.split(line)
    for word in words[1:]:  # directories of the checkout that the command names (docs/figures/...) exist there too
        if not word.startswith("-") and (ROOT / word).is_dir():
            (tmp_path / word).mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "COLUMNS": "100"}
    done = subprocess.run([sys.executable, "-m", "wavecontact", *words[1:]], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=1200, check=False)
    assert done.returncode == 0, f"{line}\n{done.stderr[-3000:]}"
    for i, word in enumerate(words[:-1]):
        if word in PATH_OPTIONS:
            assert (tmp_path / words[i + 1]).exists(), f"{line}: did not write {words[i + 1]}"
