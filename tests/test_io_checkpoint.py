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


# ----------------------------------------------------------------------------
# Rows in chunk files (RowChunks)
# ----------------------------------------------------------------------------


def _rows(start, stop):
    """Rows ``start <= j < stop`` of a made-up run: row j holds j (so any lost or repeated row shows)."""
    j = np.arange(start, stop)
    return {"j": j.astype(float), "pair": (j % 2).astype(np.int8), "block": np.repeat(j[:, None], 3, axis=1) * 0.5}


def _save(chunks, count, heads):
    chunks.save(count, _rows, lambda table: heads.append({k: v.copy() for k, v in table.items()}))


def test_row_chunks_write_each_row_a_logarithmic_number_of_times_and_read_back_every_row(tmp_path, monkeypatch):
    written = []  # rows per chunk written
    original = ckpt._write
    monkeypatch.setattr(ckpt, "_write", lambda path, *a: (written.append(a[-1]["j"].size), original(path, *a))[1])
    chunks = ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION)
    heads, every, saves = [], 7, 64
    for k in range(1, saves + 1):
        _save(chunks, every * k, heads)
        files = sorted(p.name for p in tmp_path.glob("c.rows-*.npz"))
        assert len(files) == k.bit_count()  # the chunks are the binary digits of the checkpoint count
        assert files == sorted(chunks.path(a, b).name for a, b, _c in chunks.chunks)
    # every checkpoint writes the rows since the last one plus merged ones: at most log2(saves) + 1 times each row
    assert sum(written) <= (np.log2(saves) + 1) * every * saves
    assert sum(written) < every * saves * (saves + 1) / 2 / 5  # rewriting every row each time: the square
    loaded = ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION).load(heads[-1])
    for name, value in _rows(0, every * saves).items():
        np.testing.assert_array_equal(loaded[name], value)
        assert loaded[name].dtype == value.dtype


def test_row_chunks_an_earlier_checkpoint_still_reads_and_stale_chunks_are_discarded(tmp_path):
    chunks = ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION)
    heads = []
    for count in (5, 10, 15):
        _save(chunks, count, heads)
    # a write interrupted after its chunk, before its checkpoint: the last checkpoint's table still reads
    (tmp_path / "c.rows-000000010-000000020.npz").write_bytes(b"half")
    resumed = ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION)
    np.testing.assert_array_equal(resumed.load(heads[-1])["j"], np.arange(15.0))
    resumed.discard_unlisted()
    assert sorted(p.name for p in tmp_path.glob("c.rows-*")) == ["c.rows-000000000-000000010.npz",
                                                                  "c.rows-000000010-000000015.npz"]
    _save(resumed, 20, heads)  # merges [10, 15) and [15, 20), then [0, 10) and [10, 20)
    assert [p.name for p in tmp_path.glob("c.rows-*")] == ["c.rows-000000000-000000020.npz"]


def test_row_chunks_refuse_a_missing_or_foreign_chunk_and_a_table_with_gaps(tmp_path):
    chunks = ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION)
    heads = []
    for count in (4, 6):
        _save(chunks, count, heads)
    table = heads[-1]
    other = ckpt.RowChunks(tmp_path / "other" / "c.npz", SCHEMA, VERSION)
    other.save(4, lambda a, b: {name: v + 1 for name, v in _rows(a, b).items()}, lambda t: None)
    (tmp_path / "other" / "c.rows-000000000-000000004.npz").replace(tmp_path / "c.rows-000000000-000000004.npz")
    with pytest.raises(CheckpointError, match="not the one it lists") as info:
        ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION).load(table)
    assert "\n" not in str(info.value)
    (tmp_path / "c.rows-000000000-000000004.npz").unlink()
    with pytest.raises(CheckpointError, match="c.rows-000000000-000000004.npz is missing"):
        ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION).load(table)
    with pytest.raises(ValueError, match="gaps"):
        ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION).load({**table, "chunks/start": np.array([0, 5])})
    with pytest.raises(ValueError, match="malformed"):
        ckpt.RowChunks(tmp_path / "c.npz", SCHEMA, VERSION).load({**table, "chunks/stop": np.array([4.0, 6.0])})
