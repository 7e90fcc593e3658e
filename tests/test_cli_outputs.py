"""Every command lists the files it wrote, once, on stderr and under ``files_written`` in its JSON;
progress bars appear only on a terminal (one rule, in :class:`wavecontact.progress.Progress`)."""

import io
import json
import re
import sys
from pathlib import Path

import pytest

from wavecontact.cli import main
from wavecontact.progress import Progress


class _Stream(io.StringIO):
    def __init__(self, tty):
        super().__init__()
        self._tty = tty

    def isatty(self):
        return self._tty


@pytest.mark.parametrize("enabled", [True, None])
def test_progress_draws_a_bar_on_a_terminal_only(monkeypatch, enabled):
    pipe, terminal = _Stream(False), _Stream(True)
    for stream in (pipe, terminal):
        monkeypatch.setattr(sys, "stderr", stream)
        with Progress(5, "demo", enabled=enabled) as bar:
            for _ in range(5):
                bar.advance()
        assert bar.done == 5
    assert pipe.getvalue() == ""
    assert "demo" in terminal.getvalue() and "5/5" in terminal.getvalue()


def test_progress_disabled_draws_nothing_even_on_a_terminal(monkeypatch):
    terminal = _Stream(True)
    monkeypatch.setattr(sys, "stderr", terminal)
    with Progress(3, "demo", enabled=False) as bar:
        bar.advance(3)
    assert terminal.getvalue() == ""


def _wrote(err: str) -> list:
    return re.findall(r"^wavecontact: wrote (.*)$", err, flags=re.MULTILINE)


def _clean(err: str) -> None:
    """No progress bar, no cursor codes in redirected stderr."""
    assert "\r" not in err and "\x1b[" not in err and "%|" not in err, err


# (argv builder from the folder, JSON on stdout?, files expected below the folder)
RUNS = {
    "ring": (lambda d: ["ring", "--gamma", "0.6", "--kappa", "400", "--modes", "4", "--collisions", "8",
                        "--out", str(d / "r"), "--json"], True, 9),
    "equipartition": (lambda d: ["equipartition", "--gamma", "0.6", "--kappa", "400", "--modes", "2", "3",
                                 "--collisions", "5", "--realisations", "1", "--out", str(d / "e"), "--json"], True, 3),
    "markov": (lambda d: ["markov", "--gamma", "0.6", "--rule", "glauber", "--steps", "100", "--out", str(d / "m"),
                          "--plot", str(d / "m.png"), "--json"], True, 5),
    "ensemble": (lambda d: ["ensemble", "--gamma", "0.6", "--kappa", "100", "--temperature", "0.5", "--samples", "4",
                            "--seed", "1", "--bath-modes", "20", "--out", str(d / "en"), "--plot", str(d / "en.png"),
                            "--json"], True, 5),
    "bath-figure": (lambda d: ["bath-figure", "4", "--samples", "4", "--bath-modes", "10", "--out", str(d / "f4.png"),
                               "--json", str(d / "f4.json")], False, 2),
    "restitution-table": (lambda d: ["restitution-table", "--gamma", "0.6", "--temperature", "0.5", "--samples", "4",
                                     "--seed", "2", "--bath-modes", "10", "--levels", "5", "--out", str(d / "t.csv"),
                                     str(d / "t.json")], False, 2),
    "gas": (lambda d: ["gas", "--rods", "10", "--collisions", "100", "--rule", "fixed", "--restitution", "0.9",
                       "--out", str(d / "g"), "--json"], True, 4),
    "map": (lambda d: ["map", "--impedance-ratio", "0.5,2", "--time-ratio", "0.5,2", "--out", str(d / "map")], False, 3),
}


@pytest.mark.parametrize("name", sorted(RUNS))
def test_files_written_are_listed_once_and_no_bar_goes_into_redirected_stderr(tmp_path, capsys, name):
    build, as_json, count = RUNS[name]
    assert main(build(tmp_path)) == 0
    captured = capsys.readouterr()
    _clean(captured.err)
    listed = _wrote(captured.err)
    assert len(listed) == len(set(listed)) == count, listed
    assert "wrote" not in captured.out
    files = sorted(str(p) for p in tmp_path.rglob("*") if p.is_file())
    for entry in listed:
        path = entry.split(" (")[0]
        if "*" in path:  # a summary of many files: pattern and count
            matches = sorted(Path(path).parent.glob(Path(path).name))
            assert entry.endswith(f"({len(matches)} file{'s' if len(matches) != 1 else ''})")
            files = [f for f in files if Path(f) not in matches]
        else:
            assert Path(path).is_file(), path
            files.remove(str(Path(path)))
    assert not [f for f in files if not Path(f).name.startswith(".")], f"written but not listed: {files}"
    if as_json:
        record = json.loads(captured.out)
        assert record["files_written"] == listed


def test_no_bar_goes_into_a_pipe(tmp_path):
    """bath-figure 8 wrote 40 tqdm lines with cursor codes into a redirected stderr; now only its file list."""
    import subprocess

    done = subprocess.run([sys.executable, "-m", "wavecontact", "bath-figure", "8", "--samples", "2", "--bath-modes",
                           "10", "--out", str(tmp_path / "f8.png")], capture_output=True, text=True, timeout=600,
                          check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr == f"wavecontact: wrote {tmp_path / 'f8.png'}\n"
