"""The run controller: cadence, signals as a clean stop with a checkpoint, the output lock, folder claims,
and tampered checkpoints (checksum recomputed) refused in one line."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from wavecontact.errors import InvalidParameterError
from wavecontact.io import checkpoint as ckpt
from wavecontact.io.run_controller import (
    LOCK_NAME,
    OutputLock,
    RunController,
    RunSettings,
    claim_folder,
    write_summary,
)


def tamper(path, change):
    """Rewrite a checkpoint with ``change(arrays)`` applied and its checksum recomputed (a crafted file)."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: np.array(data[name]) for name in data.files}
    meta = json.loads(str(arrays.pop("__checkpoint__")))
    change(arrays)
    meta["checksum"] = ckpt.array_checksum(arrays)
    with open(path, "wb") as handle:
        np.savez(handle, __checkpoint__=np.asarray(json.dumps(meta, sort_keys=True)), **arrays)


def _dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


# ----------------------------------------------------------------------------
# Cadence
# ----------------------------------------------------------------------------


def test_checkpoints_when_the_count_crosses_a_multiple_and_at_the_end():
    saved = []
    with RunController(10, "t", save=lambda: saved.append(run.done), every=4) as run:
        for count in (1, 2, 2, 3, 1, 1):  # 1 3 5 8 9 10
            run.advance(count)
    assert saved == [5, 8, 10]


def test_checkpoints_by_wall_time(monkeypatch):
    import wavecontact.io.run_controller as rc

    clock = [0.0]
    monkeypatch.setattr(rc.time, "monotonic", lambda: clock[0])
    saved = []
    with RunController(100, "t", save=lambda: saved.append(run.done), seconds=10.0) as run:
        for _ in range(5):
            clock[0] += 4.0
            run.advance()
    assert saved == [3]  # 12 s after the start; the next would be due at 22 s


def test_no_checkpoint_at_an_inconsistent_point():
    saved = []
    with RunController(4, "t", save=lambda: saved.append(run.done), every=1) as run:
        run.advance(2, consistent=False)
        run.advance(2)
    assert saved == [4]


# ----------------------------------------------------------------------------
# Signals
# ----------------------------------------------------------------------------


def _interrupted_at_step_7(every, interrupt):
    """Run 100 steps, ``interrupt()`` inside step 7; return (checkpoints written, messages logged)."""
    saved, messages = [], []
    run = RunController(100, "t", unit="step", save=lambda: saved.append(run.done), every=every,
                        log=messages.append)
    with pytest.raises(KeyboardInterrupt), run:
        for step in range(100):
            if step == 7:
                interrupt()
            run.advance()
    return saved, messages


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_stops_at_the_next_consistent_point_with_a_checkpoint(name):
    saved, messages = _interrupted_at_step_7(50, lambda: os.kill(os.getpid(), getattr(signal, name)))
    assert saved == [8]  # the signal arrived inside step 7: handled after it, with a checkpoint of it
    assert messages == ["interrupted; run again to resume from the checkpoint after step 8"]
    # the handlers are restored afterwards
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_exception_inside_a_step_writes_no_checkpoint():
    def interrupt():
        raise KeyboardInterrupt  # the state may be half-updated: the last checkpoint stays

    saved, messages = _interrupted_at_step_7(5, interrupt)
    assert saved == [5]
    assert messages == ["interrupted; run again to resume from the checkpoint after step 5"]


# ----------------------------------------------------------------------------
# The lock and the folder
# ----------------------------------------------------------------------------


def test_a_second_writer_is_refused_in_one_line(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK_NAME).write_text(f"{holder.pid} {os.uname().nodename}\n")
        with pytest.raises(InvalidParameterError, match=f"in use by another wavecontact run \\(pid {holder.pid}") as info:
            OutputLock(tmp_path).acquire()
        assert "\n" not in str(info.value)
    finally:
        holder.kill()
        holder.wait()
    with OutputLock(tmp_path):  # its process ended: the lock is stale and taken over
        assert (tmp_path / LOCK_NAME).read_text().split()[0] == str(os.getpid())
    assert not (tmp_path / LOCK_NAME).exists()


def test_a_stale_lock_is_taken_over(tmp_path):
    (tmp_path / LOCK_NAME).write_text(f"{_dead_pid()} {os.uname().nodename}\n")
    with RunController(1, "t", out_dir=tmp_path) as run:
        run.advance()
    assert not (tmp_path / LOCK_NAME).exists()


def test_two_runs_into_one_folder_in_one_process_are_refused(tmp_path):
    with OutputLock(tmp_path):
        with pytest.raises(InvalidParameterError, match="already used"):
            OutputLock(tmp_path).acquire()
        assert (tmp_path / LOCK_NAME).exists()  # the refused one left the holder's lock alone


def test_a_file_in_place_of_the_folder_is_refused_in_one_line(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(InvalidParameterError, match="exists and is not a directory"):
        OutputLock(tmp_path / "file").acquire()


def test_claim_folder(tmp_path):
    assert claim_folder(tmp_path, ["c.npz"], resume=False, overwrite=False) is False
    with pytest.raises(InvalidParameterError, match="holds no checkpoint"):
        claim_folder(tmp_path, ["c.npz"], resume=True, overwrite=False)
    (tmp_path / "c.npz").write_bytes(b"x")
    with pytest.raises(InvalidParameterError, match="another run's checkpoint .*--resume.*--overwrite"):
        claim_folder(tmp_path, ["c.npz"], resume=False, overwrite=False)
    assert claim_folder(tmp_path, ["c.npz"], resume=True, overwrite=False) is True
    assert claim_folder(tmp_path, ["c.npz"], resume=False, overwrite=True) is False
    assert not (tmp_path / "c.npz").exists()


def test_summary_json_is_standard_json(tmp_path):
    path = write_summary(tmp_path / "s.json", {"a": float("inf"), "b": np.float64(0.5), "c": [np.int64(2)]})
    assert json.loads(path.read_text(), parse_constant=lambda c: pytest.fail(f"non-standard constant {c}")) == {
        "a": "inf", "b": 0.5, "c": [2]}


def test_no_hand_written_replace_outside_atomic_write():
    """Every file is written through io.files.atomic_write (the one os.replace)."""
    import wavecontact

    root = os.path.dirname(wavecontact.__file__)
    offenders = []
    for folder, _dirs, files in os.walk(root):
        for name in files:
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                with open(path, encoding="utf-8") as handle:
                    text = handle.read()
                if "os.replace(" in text and not path.endswith(os.path.join("io", "files.py")):
                    offenders.append(path)
                if '.replace("Infinity"' in text:
                    offenders.append(path)
    assert not offenders


def test_run_settings_gather_the_flat_keywords_into_one_object():
    """The one path from ``f(..., out=..., executor=...)`` to ``RunSettings``: the fields are taken out of the
    keywords (the rest stay: solver options), the same object as given whole; both ways at once is refused."""
    keywords = {"out": "runs/a", "batch_size": 7, "rtol": 1e-6}
    settings = RunSettings.gather(None, keywords)
    assert settings == RunSettings(out="runs/a", batch_size=7) and keywords == {"rtol": 1e-6}
    assert RunSettings.gather(None, {}) == RunSettings()
    whole = RunSettings(progress=True)
    keywords = {"rtol": 1e-6}
    assert RunSettings.gather(whole, keywords) is whole and keywords == {"rtol": 1e-6}
    with pytest.raises(InvalidParameterError, match="^overwrite: give it in run=RunSettings"):
        RunSettings.gather(whole, {"overwrite": True})
    with pytest.raises(InvalidParameterError, match="run must be a RunSettings, got dict"):
        RunSettings.gather({"out": "x"}, {})
