"""Checkpoints: no pickle, a checksum, a schema, the build that wrote them; every bad file refused in one line."""

from __future__ import annotations

import os
import pickle
import stat

import numpy as np
import pytest

from wavecontact.errors import CheckpointError, InvalidParameterError
from wavecontact.io import checkpoint as ckpt
from wavecontact.io.files import atomic_write, check_output_directory, check_output_file

SCHEMA, VERSION = "wavecontact.test", 3
PARAMETERS = {"gamma": 0.6, "modes": 5, "kappa": "inf"}


def _arrays():
    return {"q": np.linspace(0.0, 1.0, 7), "count": np.asarray(3), "pair": np.array([0, 1, 0], dtype=np.int8)}


def _write(path):
    return ckpt.write_checkpoint(path, SCHEMA, VERSION, PARAMETERS, _arrays())


def test_round_trip(tmp_path):
    path = _write(tmp_path / "c.npz")
    arrays, meta = ckpt.read_checkpoint(path, SCHEMA, VERSION, PARAMETERS)
    for name, value in _arrays().items():
        np.testing.assert_array_equal(arrays[name], value)
        assert arrays[name].dtype == value.dtype
    assert meta["parameters"] == PARAMETERS


def test_files_get_ordinary_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        path = _write(tmp_path / "c.npz")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_a_pickled_payload_is_never_unpickled(tmp_path):
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    path = tmp_path / "evil.npz"
    with open(path, "wb") as handle:
        pickle.dump(Payload(), handle)
    with pytest.raises(CheckpointError, match="unreadable"):
        ckpt.read_checkpoint(path, SCHEMA, VERSION)
    np.savez(tmp_path / "objects.npz", q=np.array([Payload()], dtype=object))
    with pytest.raises(CheckpointError):
        ckpt.read_checkpoint(tmp_path / "objects.npz", SCHEMA, VERSION)
    assert not marker.exists()


def test_one_flipped_bit_fails_the_checksum(tmp_path):
    path = _write(tmp_path / "c.npz")
    with np.load(path, allow_pickle=False) as data:
        payload = {name: np.array(data[name]) for name in data.files}
    q = payload["q"].view(np.uint64).copy()
    q[3] ^= np.uint64(1)  # one bit of one float
    payload["q"] = q.view(np.float64)
    np.savez(path, **payload)
    with pytest.raises(CheckpointError, match="checksum"):
        ckpt.read_checkpoint(path, SCHEMA, VERSION, PARAMETERS)


@pytest.mark.parametrize(
    "change, check",
    [
        ({"schema": "wavecontact.other"}, "other"),
        ({"version": VERSION + 1}, "format version"),
        ({"package_version": "0.0.0"}, "written by wavecontact 0.0.0"),
        ({"kernel_digest": "0" * 64}, "different build of the compiled kernels"),
    ],
)
def test_each_metadata_check_refuses_with_its_reason(tmp_path, change, check):
    import json

    path = _write(tmp_path / "c.npz")
    with np.load(path, allow_pickle=False) as data:
        payload = {name: np.array(data[name]) for name in data.files}
    meta = json.loads(str(payload["__checkpoint__"]))
    meta.update(change)
    payload["__checkpoint__"] = np.asarray(json.dumps(meta))
    np.savez(path, **payload)
    with pytest.raises(CheckpointError, match=check) as info:
        ckpt.read_checkpoint(path, SCHEMA, VERSION, PARAMETERS)
    assert "\n" not in str(info.value) and "delete it" in str(info.value)


def test_other_parameters_and_missing_records_are_refused(tmp_path):
    path = _write(tmp_path / "c.npz")
    with pytest.raises(CheckpointError, match="modes=5 \\(now 6\\)"):
        ckpt.read_checkpoint(path, SCHEMA, VERSION, {**PARAMETERS, "modes": 6})
    np.savez(tmp_path / "plain.npz", q=np.zeros(3))
    with pytest.raises(CheckpointError, match="not a wavecontact checkpoint"):
        ckpt.read_checkpoint(tmp_path / "plain.npz", SCHEMA, VERSION)
    (tmp_path / "empty.npz").write_bytes(b"")
    with pytest.raises(CheckpointError, match="unreadable"):
        ckpt.read_checkpoint(tmp_path / "empty.npz", SCHEMA, VERSION)


def test_atomic_write_leaves_nothing_behind_on_failure(tmp_path):
    def broken(handle):
        handle.write(b"partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(tmp_path / "x.bin", broken)
    assert list(tmp_path.iterdir()) == []


def test_output_paths_are_checked_before_work(tmp_path):
    (tmp_path / "dir").mkdir()
    with pytest.raises(InvalidParameterError, match="--plot: .* is a directory"):
        check_output_file("--plot", tmp_path / "dir", (".png",))
    with pytest.raises(InvalidParameterError, match="must end in one of .png"):
        check_output_file("--plot", tmp_path / "x.txt", (".png",))
    (tmp_path / "file").write_text("")
    with pytest.raises(InvalidParameterError, match="--out: .* exists and is not a directory"):
        check_output_directory("--out", tmp_path / "file")
    with pytest.raises(InvalidParameterError, match="not a directory"):
        check_output_file("--plot", tmp_path / "file" / "x.png", (".png",))
    assert check_output_file("--plot", tmp_path / "new" / "x.png", (".png",)).name == "x.png"
