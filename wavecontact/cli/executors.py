"""Where a command's batches run: here, local processes or a Dask cluster, with bounded waits.

``--scheduler ADDRESS`` connects to a running ``dask.distributed`` scheduler
within :data:`CONNECT_TIMEOUT_S`.  While the run lasts a watchdog thread
checks the cluster every second; when the scheduler has been unreachable or
the cluster has had no worker for :data:`LOST_AFTER_S` seconds, it stops the
run, which then ends with one line (``wavecontact: error: ...``) instead of
waiting forever.

Dask trusts the cluster: results come back pickled and are unpickled here, so
connect only to a scheduler whose workers you trust.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from contextlib import contextmanager

from ..errors import InvalidParameterError

__all__ = ["CONNECT_TIMEOUT_S", "LOST_AFTER_S", "executor_from", "lost_cluster"]

#: Seconds to reach the scheduler before giving up.
CONNECT_TIMEOUT_S = 3.0
#: Seconds without a reachable scheduler, or without any worker, before a run is stopped.
LOST_AFTER_S = 30.0

_LOST = []  # the reason the watchdog stopped the run, read by cli.main


def lost_cluster() -> str | None:
    """Why the watchdog stopped the current run (None: it did not)."""
    return _LOST[0] if _LOST else None


def _ignore_interrupts() -> None:
    """Worker processes ignore SIGINT (no traceback from each of them on Ctrl-C) and end on SIGTERM (a worker
    forked inside a run inherits that run's handlers, which would keep it alive and talking)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def connect(scheduler: str):
    """A ``distributed.Client`` of ``scheduler``, or a one-line refusal within :data:`CONNECT_TIMEOUT_S`."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover
        raise InvalidParameterError("--scheduler needs dask.distributed installed") from None
    import logging

    # the client logs a traceback when the scheduler goes away; the command says it in one line instead
    for name in ["distributed", *logging.root.manager.loggerDict]:
        if name.split(".")[0] == "distributed":
            logging.getLogger(name).setLevel(logging.CRITICAL)
    try:
        return Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S:g}s")
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InvalidParameterError(f"--scheduler: cannot reach the Dask scheduler at {scheduler!r} within "
                                    f"{CONNECT_TIMEOUT_S:g} s: {reason}") from None


class Watchdog(threading.Thread):
    """Stops the main thread (as Ctrl-C would) when the cluster has been lost for ``patience`` seconds.

    ``probe()`` returns None while the cluster is fine, else the reason it is not.
    """

    def __init__(self, probe, patience: float = LOST_AFTER_S, interval: float = 1.0):
        super().__init__(name="wavecontact-dask-watchdog", daemon=True)
        self.probe, self.patience, self.interval = probe, float(patience), float(interval)
        self._stop_event = threading.Event()

    def run(self):
        since = None
        while not self._stop_event.wait(self.interval):
            try:
                reason = self.probe()
            except Exception as exc:  # noqa: BLE001 - a failing probe is itself a lost cluster
                reason = f"the scheduler does not answer ({type(exc).__name__})"
            if reason is None:
                since = None
                continue
            since = time.monotonic() if since is None else since
            if time.monotonic() - since >= self.patience:
                _LOST[:] = [f"{reason} for {self.patience:g} s; the run was stopped"]
                # a real signal: it wakes the main thread from a blocking wait (interrupt_main would not)
                os.kill(os.getpid(), signal.SIGINT)
                return

    def stop(self):
        self._stop_event.set()


def _client_probe(client):
    def probe():
        status = getattr(client, "status", "running")
        if status not in ("running", "newly-created"):
            return f"the Dask scheduler was lost (client {status})"
        if not client.scheduler_info().get("workers"):
            return "the Dask cluster has no worker"
        return None

    return probe


def _quiet_about_cancelled_futures(previous):
    """A ``threading.excepthook`` that drops the pool's own complaint, once its workers were terminated, that
    it cannot fail a future already cancelled (``InvalidStateError`` in Python 3.11's process pool)."""
    from concurrent.futures import InvalidStateError

    def hook(args):
        if not issubclass(args.exc_type, InvalidStateError):
            previous(args)

    return hook


@contextmanager
def executor_from(workers: int, scheduler):
    """A process pool, a Dask client (watched) or nothing (one worker), closed afterwards."""
    if scheduler:
        client = connect(scheduler)
        _LOST.clear()
        watchdog = Watchdog(_client_probe(client))
        watchdog.start()
        try:
            yield client
        finally:
            watchdog.stop()
            try:
                client.close(timeout=CONNECT_TIMEOUT_S)
            except Exception:  # noqa: BLE001, S110 - a lost cluster cannot be closed cleanly
                pass
    elif workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        # Ctrl-C reaches the whole process group: the workers leave it to this process, which stops them
        pool = ProcessPoolExecutor(max_workers=workers, initializer=_ignore_interrupts)
        try:
            yield pool
        except BaseException:
            processes = list((getattr(pool, "_processes", None) or {}).values())
            manager = getattr(pool, "_executor_manager_thread", None)
            pool.shutdown(wait=False, cancel_futures=True)
            previous = threading.excepthook
            threading.excepthook = _quiet_about_cancelled_futures(previous)
            try:
                for process in processes:  # running batches are abandoned, not waited for
                    process.terminate()
                if manager is not None:
                    manager.join(timeout=CONNECT_TIMEOUT_S)
            finally:
                threading.excepthook = previous
            raise
        pool.shutdown()
    else:
        yield None
