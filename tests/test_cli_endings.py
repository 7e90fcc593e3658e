"""How a command ends when the work fails underneath it: one line, a stated exit status, never a traceback.

Ctrl-C (also inside a numba kernel, where it surfaces as a SystemError), running out of memory, a dead
worker process, a lost Dask scheduler or cluster: each ends with one line on stderr.
"""

import asyncio
import concurrent.futures
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from wavecontact.cli import executors, main

ARGV = ["compare", "--gamma", "0.6", "--kappa", "100", "--no-progress"]


def _kernel_interrupt():
    """What numba raises when Ctrl-C arrives inside a compiled function."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as exc:
        raise SystemError("CPUDispatcher(<function kernel>) returned a result with an exception set") from exc


def _broken_pool():
    from concurrent.futures.process import BrokenProcessPool

    raise BrokenProcessPool("A process in the process pool was terminated abruptly")


@pytest.mark.parametrize("failure, status, line", [
    (KeyboardInterrupt, 130, "wavecontact: interrupted"),
    (_kernel_interrupt, 130, "wavecontact: interrupted"),
    (MemoryError, 2, "wavecontact: error: out of memory"),
    (_broken_pool, 2, "wavecontact: error: a worker process died"),
    (concurrent.futures.CancelledError, 2, "wavecontact: error: the Dask scheduler or its workers were lost"),
    (asyncio.CancelledError, 2, "wavecontact: error: the Dask scheduler or its workers were lost"),
])
def test_failures_under_the_work_end_with_one_line(monkeypatch, capsys, failure, status, line):
    from wavecontact.studies import compare

    def fail(*args, **kwargs):
        failure() if callable(failure) and not isinstance(failure, type) else (_ for _ in ()).throw(failure())

    monkeypatch.setattr(compare, "compare_solvers", fail)
    assert main(list(ARGV)) == status
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [captured.err.strip()] and captured.err.startswith(line), captured.err
    assert "Traceback" not in captured.err


def test_a_reader_that_closes_the_pipe_first_ends_the_command_quietly_with_status_141():
    """``wavecontact ... | head``: the reader is gone before the answer is printed; no traceback, no error line."""
    command = [sys.executable, "-m", "wavecontact", "collide", "--gamma", "0.6", "--kappa", "inf"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    process.stdout.close()  # before the child has even imported the package
    try:
        _out, err = process.communicate(timeout=240)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 141, err
    assert "Traceback" not in err and "Broken pipe" not in err and "Exception ignored" not in err, err


def test_a_broken_pipe_elsewhere_than_standard_output_is_an_error_in_one_line(monkeypatch, capsys):
    from wavecontact import cli
    from wavecontact.studies import compare

    def fail(*args, **kwargs):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(compare, "compare_solvers", fail)
    monkeypatch.setattr(cli, "_stdout_closed", lambda: False)  # pytest's capture has no pipe to poll
    assert main(list(ARGV)) == 2
    err = capsys.readouterr().err
    assert err == "wavecontact: error: [Errno 32] Broken pipe\n"


def test_a_watchdog_that_finds_the_cluster_lost_stops_the_run_with_its_reason(monkeypatch, capsys):
    """The watchdog interrupts the main thread; main reports the reason, not 'interrupted'."""
    from wavecontact.studies import compare

    monkeypatch.setattr(executors, "_LOST", [])

    def wait_for_the_watchdog(*args, **kwargs):
        dog = executors.Watchdog(lambda: "the Dask cluster has no worker", patience=0.2, interval=0.05)
        dog.start()
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            time.sleep(0.01)
        raise AssertionError("the watchdog did not stop the run")

    monkeypatch.setattr(compare, "compare_solvers", wait_for_the_watchdog)
    started = time.monotonic()
    assert main(list(ARGV)) == 2
    err = capsys.readouterr().err
    assert err == "wavecontact: error: the Dask cluster has no worker for 0.2 s; the run was stopped\n"
    assert time.monotonic() - started < 10


def test_a_watchdog_keeps_quiet_while_the_cluster_answers():
    calls = []
    dog = executors.Watchdog(lambda: calls.append(1), patience=0.1, interval=0.02)
    dog.start()
    time.sleep(0.3)
    dog.stop()
    dog.join(5)
    assert len(calls) >= 3 and executors.lost_cluster() is None


def test_the_client_probe_reports_a_closed_client_and_an_empty_cluster():
    class Client:
        status, workers = "running", {"w": {}}

        def scheduler_info(self):
            return {"workers": self.workers}

    client = Client()
    probe = executors._client_probe(client)
    assert probe() is None
    client.workers = {}
    assert "no worker" in probe()
    client.status = "closed"
    assert "scheduler was lost" in probe()


def test_ctrl_c_ends_a_running_command_with_status_130(tmp_path):
    """A real SIGINT into a ring run (numba kernels or Python, wherever it lands)."""
    command = [sys.executable, "-m", "wavecontact", "ring", "--gamma", "0.6", "--kappa", "100", "--modes", "400",
               "--collisions", "500", "--out", str(tmp_path / "ring")]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and not (tmp_path / "ring").exists() and process.poll() is None:
            time.sleep(0.2)
        time.sleep(3.0)  # inside the collisions
        process.send_signal(signal.SIGINT)
        _out, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 130, err
    assert err.strip().splitlines()[-1] == "wavecontact: interrupted", err
    assert "Traceback" not in err


def test_a_scheduler_at_a_closed_port_is_given_up_within_the_connect_timeout():
    started = time.monotonic()
    with pytest.raises(Exception) as caught, executors.executor_from(0, "tcp://127.0.0.1:9"):
        pass
    assert "cannot reach" in str(caught.value) and "--scheduler" in str(caught.value)
    assert time.monotonic() - started < executors.CONNECT_TIMEOUT_S + 10
    assert not [t for t in threading.enumerate() if t.name == "wavecontact-dask-watchdog"]


def test_the_entry_points_behind_the_commands_refuse_bad_paths_by_name(tmp_path):
    """ensemble(out=FILE) and RingRun.load_npz(garbage): a WavecontactError naming the problem, not an OSError."""
    from wavecontact.errors import CheckpointError, InvalidParameterError
    from wavecontact.studies.ensemble import ensemble
    from wavecontact.studies.ring import RingRun

    a_file = tmp_path / "afile"
    a_file.write_text("x")
    with pytest.raises(InvalidParameterError, match="not a directory"):
        ensemble(0.6, 100.0, 1.0, 2, 0, bath_modes=10, out=a_file)
    for content in (b"", b"garbage", b"PK\x03\x04broken"):
        a_file.write_bytes(content)
        with pytest.raises(CheckpointError, match="not a ring run"):
            RingRun.load_npz(a_file)
    with pytest.raises(CheckpointError, match="no such file"):
        RingRun.load_npz(tmp_path / "missing.npz")


def test_ctrl_c_at_a_terminal_stops_the_worker_processes_too_in_one_line():
    """A terminal's Ctrl-C reaches the whole process group: the workers stay silent, the run ends at once."""
    command = [sys.executable, "-m", "wavecontact", "ensemble", "--gamma", "0.6", "--kappa", "100", "--temperature",
               "1", "--samples", "100000", "--batch-size", "64", "--seed", "0", "--bath-modes", "100", "--workers", "2"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        workers = _wait_for_children(process, 2, timeout=120)
        time.sleep(2.0)  # the workers have set their signal handlers and are inside their first batch
        os.killpg(process.pid, signal.SIGINT)
        stopped = time.monotonic()
        _out, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    # a worker that had to compile says so once before its work (not part of the ending); nothing else
    err = "".join(line for line in err.splitlines(keepends=True) if "compiling numba kernels" not in line)
    assert process.returncode == 130 and err == "wavecontact: interrupted\n", err
    assert time.monotonic() - stopped < 30
    deadline = time.monotonic() + 30
    while workers and time.monotonic() < deadline:
        workers = [pid for pid in workers if _alive(pid)]
        time.sleep(0.05)
    assert not workers, f"worker processes {workers} outlived the command"


def _state(pid):
    """The state letter of process ``pid`` from /proc ('Z' zombie), or None if there is no such process."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rpartition(")")[2].split()[0]
    except OSError:
        return None


def _alive(pid):
    return _state(pid) not in (None, "Z", "X")


def _children(pid):
    """Process ids whose parent is ``pid`` (from /proc: Linux)."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as stat:
                    fields = stat.read().rpartition(")")[2].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry))
    return found


def _wait_for_children(process, count, timeout):
    """Wait until ``process`` has forked ``count`` live children (its worker pool) and return their ids.

    Without /proc (not Linux) wait a fixed 12 s instead and return no ids."""
    if not os.path.isdir("/proc/self"):
        time.sleep(12.0)
        return []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        children = [pid for pid in _children(process.pid) if _alive(pid)]
        if len(children) >= count:
            return children
        time.sleep(0.05)
    raise AssertionError(f"the command did not start {count} worker processes within {timeout} s")
