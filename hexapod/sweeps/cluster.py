"""Where a study's cases run on Dask: a client given (left open), a local cluster of worker
processes, or a running scheduler named by its address, which must answer as a Dask scheduler
within a stated time and have a worker.

A scheduler's address is checked for its form before any work (``tcp://HOST:PORT``); the wait
for its answer is :func:`scheduler_timeout` seconds (``HEXAPOD_SCHEDULER_TIMEOUT``, the
command's ``--scheduler-timeout``), after which the study ends with an error naming the
address, whatever listens there (nothing, a server that never answers, a web server).
"""

from __future__ import annotations

import math
import os
import re

from hexapod.errors import HexapodError
from hexapod.sweeps.cases import StudyError

#: Seconds a scheduler named by its address has, by default, to answer and to have a worker.
DEFAULT_SCHEDULER_TIMEOUT = 10.0
#: The longest wait one may ask for (a day): beyond it, a wait is a hang.
MAX_SCHEDULER_TIMEOUT = 86400.0
_PORT = re.compile(r"(?P<host>\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]@]+):(?P<port>[0-9]+)")
_UNSUPPORTED = {
    "ucx": "needs UCX and its Python bindings (ucx-py), which hexapod does not support",
    "tls": "needs certificates (a distributed Security object), which the command line cannot "
           "pass; make a Client with them and give it to hexapod.sweep(client=...)",
}


def scheduler_timeout(given: float | None = None) -> float:
    """The seconds a scheduler has to answer: ``given``, else ``HEXAPOD_SCHEDULER_TIMEOUT``,
    else :data:`DEFAULT_SCHEDULER_TIMEOUT`.

    Raises
    ------
    HexapodError
        The value given, or the environment's, is not a positive number of seconds.
    """
    where = "scheduler timeout"
    if given is None:
        text = os.environ.get("HEXAPOD_SCHEDULER_TIMEOUT", "").strip()
        if not text:
            return DEFAULT_SCHEDULER_TIMEOUT
        where = "environment variable HEXAPOD_SCHEDULER_TIMEOUT"
        try:
            given = float(text)
        except ValueError:
            raise HexapodError(f"{where}: not a number of seconds: {text!r}") from None
    if not (math.isfinite(given) and 0 < given <= MAX_SCHEDULER_TIMEOUT):
        raise HexapodError(f"{where}: must be positive seconds, at most "
                           f"{MAX_SCHEDULER_TIMEOUT:g}, got {given!r}")
    return float(given)


def scheduler_address(text: str) -> str:
    """A scheduler's address checked for its form, as ``tcp://HOST:PORT`` (``HOST:PORT``
    alone means TCP).

    Raises
    ------
    ValueError
        Saying what is wrong: another protocol (``ucx://``, ``tls://`` ...), no port, a port
        out of range.
    """
    address = str(text).strip()
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    scheme = scheme.lower()
    if scheme in _UNSUPPORTED:
        raise ValueError(f"{text!r}: the {scheme}:// protocol {_UNSUPPORTED[scheme]}; use "
                         "tcp://HOST:PORT")
    if scheme != "tcp":
        raise ValueError(f"{text!r}: the {scheme}:// protocol is not supported; use "
                         "tcp://HOST:PORT")
    match = _PORT.fullmatch(rest)
    if not match:
        raise ValueError(f"{text!r}: not a scheduler's address; write tcp://HOST:PORT (e.g. "
                         "tcp://10.0.0.5:8786)")
    if not 0 < int(match["port"]) < 65536:
        raise ValueError(f"{text!r}: port {match['port']} is not from 1 to 65535")
    return f"tcp://{match['host']}:{int(match['port'])}"


def worker_count(client) -> int:
    """The client's cluster's workers, at least 1 (1 when the scheduler does not say)."""
    try:
        return max(1, len(client.scheduler_info()["workers"]))
    except Exception:
        return 1


def _reach(address: str, timeout: float) -> None:
    """Open and close a TCP connection to ``address``: a refused connection, an unknown host
    or no route is said at once (Dask would retry it until its timeout)."""
    import socket

    host, _, port = address.removeprefix("tcp://").rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except TimeoutError:
        raise StudyError(f"scheduler {address}: cannot connect (no answer within {timeout:g} "
                         "s); check the address, or wait longer with --scheduler-timeout "
                         "SECONDS (or HEXAPOD_SCHEDULER_TIMEOUT)") from None
    except OSError as error:
        said = error.strerror or str(error) or type(error).__name__
        raise StudyError(f"scheduler {address}: cannot connect ({said})") from None


def _probe(address: str, timeout: float) -> None:
    """Connect to ``address`` and exchange Dask's handshake within ``timeout`` seconds (Dask's
    own connection waits for the answer without end, and takes a web server's reply for the
    length of a message), in a thread of its own so that a caller's running event loop does
    not matter."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.comm import connect

    _reach(address, timeout)

    async def handshake() -> None:
        comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout)
        await comm.close()

    pool = ThreadPoolExecutor(1, thread_name_prefix="hexapod-scheduler-probe")
    try:
        pool.submit(lambda: asyncio.run(handshake())).result(timeout + 5)
    except TimeoutError:
        raise StudyError(f"scheduler {address}: accepted the connection but gave no answer as "
                         f"a Dask scheduler within {timeout:g} s; check the address, or wait "
                         "longer with --scheduler-timeout SECONDS (or "
                         "HEXAPOD_SCHEDULER_TIMEOUT)") from None
    except MemoryError:
        raise StudyError(f"scheduler {address}: answered, but not as a Dask scheduler (a web "
                         "server?); check the address and port") from None
    except Exception as error:
        said = str(error).strip() or type(error).__name__
        raise StudyError(f"scheduler {address}: cannot connect ({said})") from None
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


class StudyClient:
    """A Dask client for the study, as a context manager: the one given (left open), or one
    made here on a local cluster of ``workers`` processes or on ``scheduler``'s address
    (closed at the end); ``announce`` receives the dashboard's address. The scheduler's
    address and the timeout are checked when it is made, before any work.

    Raises
    ------
    StudyError
        An address of another form or protocol (:func:`scheduler_address`).
    HexapodError
        A timeout that is not positive seconds (:func:`scheduler_timeout`).
    """

    def __init__(self, client, workers, scheduler, announce, timeout: float | None = None):
        self.given, self.workers, self.announce = client, workers, announce
        self.scheduler = self.timeout = None
        if client is None and scheduler is not None:
            try:
                self.scheduler = scheduler_address(scheduler)
            except ValueError as error:
                raise StudyError(f"scheduler {error}") from None
            self.timeout = scheduler_timeout(timeout)
        self.made: list = []

    def __enter__(self):
        if self.given is not None:
            return self.given
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise StudyError("running a study on Dask needs dask.distributed: "
                             "pip install 'hexapod[sweep]' (or run it in this process)") \
                from None
        if self.scheduler is not None:
            client = self._connect(Client)
        else:
            import logging

            import dask

            # Dask's default MALLOC_TRIM_THRESHOLD_ also turns off glibc's dynamic mmap
            # threshold in the workers: every large NumPy temporary is then mapped and unmapped
            # (75,000 more page faults and 0.1 s of system time a walking robot's case), and its
            # profiler thread samples every 10 ms; neither serves a study's short tasks
            with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_":
                                  None, "distributed.worker.profile.enabled": False}):
                cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                       processes=True, dashboard_address=":0",
                                       silence_logs=logging.ERROR,
                                       env={"OPENBLAS_NUM_THREADS": "1"})
            self.made.append(cluster)
            client = Client(cluster)
            self.made.insert(0, client)
        if self.announce is not None:
            self.announce(f"Dask dashboard: {client.dashboard_link}")
        return client

    def _connect(self, Client):
        address, timeout = self.scheduler, self.timeout
        _probe(address, timeout)
        try:
            client = Client(address, timeout=timeout)
        except Exception as error:  # it answered the probe: a failure of its own
            said = str(error).strip() or type(error).__name__
            raise StudyError(f"scheduler {address}: cannot connect ({said})") from None
        try:
            client.wait_for_workers(1, timeout=timeout)
        except Exception:
            client.close()
            raise StudyError(f"scheduler {address}: no worker joined within {timeout:g} s; "
                             f"start one (dask worker {address}), or wait longer with "
                             "--scheduler-timeout SECONDS (or HEXAPOD_SCHEDULER_TIMEOUT)") \
                from None
        self.made.append(client)
        return client

    def __exit__(self, *exc):
        for thing in self.made:
            try:
                thing.close()
            except Exception:
                pass
        return False
