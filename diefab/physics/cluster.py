"""Running drops on a Dask cluster: the client, a probe of the scheduler, and a watched gather.

A lost scheduler or a cluster left without workers ends the run in one
:class:`~diefab.core.errors.PhysicsError` within a stated time, never a hang.
"""

from __future__ import annotations

import logging
import math
import os
import time

from diefab.core.errors import PhysicsError
from diefab.physics.pool import SIGNAL_POLL

__all__ = ["DASK_STALL", "dask_client", "gather", "stall_limit"]


def dask_client(scheduler, timeout: float = 3.0):
    """``(client, owned)``: a Dask client for `scheduler` (an address or a ``distributed.Client``).

    ``owned`` is True when the client was opened here (the caller closes it).
    An address where no Dask scheduler answers fails within about `timeout`
    seconds (twice that at worst) with a :class:`PhysicsError`: nothing
    listening, a server that stays silent, or one that sends something else.
    A bad ``DIEFAB_DASK_STALL`` fails here too, before anything is dropped.
    """
    from diefab.core.extras import require

    stall_limit()

    Client = require("distributed", "dask", "--scheduler").Client
    # a lost cluster is reported by the caller as one PhysicsError, not by the client's own log lines
    for name in ("distributed", "distributed.client", "distributed.core", "distributed.comm"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise PhysicsError(f"scheduler address {scheduler!r} is not an address such as tcp://host:8786")
    _probe_scheduler(scheduler, timeout)
    try:
        return Client(scheduler, timeout=f"{timeout}s"), True
    except (OSError, TimeoutError, ValueError, TypeError, MemoryError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise PhysicsError(f"cannot reach Dask scheduler {scheduler!r}: {reason}") from None


#: Largest first message a Dask scheduler sends (its handshake is a few hundred bytes).
_HANDSHAKE_MAX = 1 << 20


def _probe_scheduler(address: str, timeout: float) -> None:
    """Check within `timeout` that a plain TCP `address` greets like a Dask scheduler.

    Dask's TCP comm starts with both ends sending a handshake: an 8-byte
    length, then that many bytes.  distributed waits for it without a time
    limit and allocates whatever length arrives, so a silent server (an HTTP
    server waits for a request) hangs the client and a chatty one makes it
    allocate exabytes.  Other schemes (tls://, ucx://, ...) are left to
    distributed's own timeout.
    """
    import socket
    import struct

    from distributed.comm import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme != "tcp":
            return
        host, port = parse_host_port(location, default_port=8786)
    except (ValueError, TypeError) as exc:
        raise PhysicsError(f"scheduler address {address!r} is not valid: {exc}") from None

    def fail(reason: str) -> None:
        raise PhysicsError(f"cannot reach Dask scheduler {address!r}: {reason}")

    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:

            def receive(size: int) -> bytes:
                data = b""
                while len(data) < size:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise TimeoutError
                    sock.settimeout(left)
                    chunk = sock.recv(min(size - len(data), 65536))
                    if not chunk:
                        fail("the server closed the connection without a Dask handshake")
                    data += chunk
                return data

            try:
                (size,) = struct.unpack("Q", receive(8))
                if not 0 < size <= _HANDSHAKE_MAX:
                    fail("the server is not a Dask scheduler (it does not speak Dask's protocol)")
                receive(size)
            except TimeoutError:
                fail(f"no Dask handshake within {timeout:g} s (is it a Dask scheduler?)")
    except OSError as exc:
        fail(f"{exc.strerror or exc}")


#: Seconds a Dask run may go without a worker before it fails, unless ``DIEFAB_DASK_STALL`` says otherwise.
DASK_STALL = 30.0


def stall_limit() -> float:
    """Seconds a run waits for a worker to join: ``DIEFAB_DASK_STALL`` if set, else :data:`DASK_STALL`.

    An adaptive cluster that takes minutes to start a worker needs a longer wait than a fixed one.
    """
    text = os.environ.get("DIEFAB_DASK_STALL", "").strip()
    if not text:
        return DASK_STALL
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not 0 < seconds < math.inf:
        raise PhysicsError(f"DIEFAB_DASK_STALL must be a positive number of seconds, not {text!r}")
    return seconds


def gather(client, futures, on_result, check_stop) -> None:
    """Hand each finished future to `on_result`; fail in one line if the cluster cannot finish.

    A run whose scheduler is gone, or whose cluster has had no worker for
    :func:`stall_limit` seconds, raises :class:`PhysicsError` instead of
    waiting forever (Dask itself would wait for a worker to come back).
    """
    from distributed import wait

    stall = stall_limit()
    pending = set(futures)
    lonely = None  # since when the cluster has had no worker
    while pending:
        try:
            ready, _ = wait(list(pending), timeout=SIGNAL_POLL, return_when="FIRST_COMPLETED")
            ready = set(ready) & pending
        except TimeoutError:
            ready = set()
        except Exception as exc:  # the scheduler went away: distributed raises many kinds
            raise PhysicsError(f"the Dask scheduler was lost ({type(exc).__name__})") from None
        for future in ready:
            pending.discard(future)
            if future.status != "finished":
                raise PhysicsError(f"a Dask batch failed or the scheduler was lost ({future.status}); the drops "
                                   "that had finished are not counted")  # fmt: skip
            try:
                on_result(future)
            except (OSError, TimeoutError) as exc:
                raise PhysicsError(f"the Dask scheduler was lost ({type(exc).__name__})") from None
        check_stop()
        if ready:
            lonely = None
            continue
        if client.status not in ("running", "connecting"):
            raise PhysicsError(f"the Dask scheduler was lost (client {client.status})")
        try:
            workers = len(client.nthreads())
        except Exception as exc:
            raise PhysicsError(f"the Dask scheduler was lost ({type(exc).__name__})") from None
        if workers:
            lonely = None
        elif lonely is None:
            lonely = time.monotonic()
        elif time.monotonic() - lonely > stall:
            raise PhysicsError(f"the Dask cluster has had no worker for {stall:g} s; start workers and run "
                               "again")  # fmt: skip
