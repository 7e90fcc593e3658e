"""The command line as a whole: --version, and --help that states every option's meaning and default."""

import argparse
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import wavecontact
from wavecontact.cli import build_parser, main

ROOT = Path(__file__).resolve().parent.parent
OUTPUT_METAVARS = {"FILE", "DIR"}  # output paths: nothing is written unless given


def subcommands():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices


def test_version_is_written_once_and_printed():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert re.fullmatch(r"\d+\.\d+\.\d+", wavecontact.__version__)
    done = subprocess.run([sys.executable, "-m", "wavecontact", "--version"], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0 and done.stdout.strip() == f"wavecontact {wavecontact.__version__}"


def test_license_is_an_spdx_expression_with_its_file():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT"
    assert "MIT License" in (ROOT / "LICENSE").read_text()


@pytest.mark.parametrize("name", sorted(subcommands()))
def test_help_explains_every_option_and_its_default(name):
    parser = subcommands()[name]
    text = parser.format_help()
    assert "%%" not in text and "%(" not in text
    for action in parser._actions:
        if not action.option_strings and not isinstance(action, argparse._SubParsersAction):
            assert action.help, f"{name}: the positional argument {action.dest} has no help text"
        if not action.option_strings or isinstance(action, argparse._HelpAction):
            continue
        flag = action.option_strings[-1]
        assert action.help, f"{name} {flag} has no help text"
        shown = parser._get_formatter()._get_help_string(action)
        takes_value = action.nargs != 0
        if takes_value and not action.required and action.metavar not in OUTPUT_METAVARS:
            assert "default" in shown, f"{name} {flag}: no default in its help {shown!r}"
        default = action.default
        if isinstance(default, (int, float, str, list, tuple)) and not isinstance(default, bool) \
                and default != argparse.SUPPRESS and not action.required:
            value = " ".join(map(str, default)) if isinstance(default, (list, tuple)) else str(default)
            assert value in " ".join(text.split()), f"{name} {flag}: default {value} not shown"


def test_help_of_solver_options_is_the_solvers_own(capsys):
    """Meaning, allowed values and default as each solver's Options dataclass declares them."""
    from wavecontact.solvers import get_solver
    from wavecontact.solvers.base import option_help

    with pytest.raises(SystemExit):
        main(["collide", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for solver, names in (("delay", ("rtol", "max_steps")), ("fem", ("elements", "order", "mass")),
                          ("modal", ("modes",))):
        rows = {row[0]: row for row in option_help(get_solver(solver).Options)}
        for name in names:
            _, default, allowed, meaning = rows[name]
            assert meaning in text and allowed in text, (solver, name)
            shown = f"{default:g}" if isinstance(default, float) else str(default)
            assert f"{meaning}; {allowed} (default: {shown})" in text


def test_ring_json_lists_its_files(tmp_path, capsys):
    import json

    out = tmp_path / "ring"
    assert main(["ring", "--gamma", "0.6", "--kappa", "400", "--modes", "4", "--collisions", "8",
                 "--out", str(out), "--json", "--no-progress"]) == 0
    captured = capsys.readouterr()
    record = json.loads(captured.out)
    assert record["gamma"] == 0.6 and record["files_written"]
    for name in record["files_written"]:
        pattern = name.split(" (")[0]  # many files of one kind: "DIR/pattern (N files)"
        assert any(Path(pattern).parent.glob(Path(pattern).name)) and f"wrote {name}" in captured.err
    assert str(out / "summary.json") in record["files_written"]
