"""The Dask cluster a sweep runs on: a local one sized to the machine, or an existing one by its scheduler's address.

Dask is imported when a client is made, not with this module: the command line reads ``add_cluster_arguments`` for
every command it parses, and importing Dask costs about 2 s."""

from __future__ import annotations

import contextlib
import logging
import os
import socket
from collections.abc import Iterator

CONNECT_TIMEOUT_S = 20  # the longest wait for a scheduler given by its address to answer as Dask does
REACH_TIMEOUT_S = 3.0  # the longest wait for its host to accept a connection at all


# Dask's nannies start workers with MALLOC_TRIM_THRESHOLD_=65536 (distributed.nanny.pre-spawn-environ), which turns
# off glibc's adaptive mmap threshold: every image-sized array is then mapped and unmapped afresh. In one unsaved run
# of benchmarks/sweep_speed.py a run on a worker took 0.58 s with it against 0.39 s one after another on one thread
# (about 1.5 times as long), and 0.22 s against 0.24 s without it; the saved results hold no measurement of it. A run
# keeps no memory between tasks that trimming would give back, so the local cluster's workers start without it.
WORKER_ENVIRONMENT_UNSET = ("MALLOC_TRIM_THRESHOLD_",)


@contextlib.contextmanager
def cluster_client(scheduler: str | None = None, workers: int | None = None) -> Iterator:
    """A Dask client: of the scheduler at ``scheduler`` (``tcp://HOST:PORT``), else at ``DASK_SCHEDULER_ADDRESS``,
    else of a new local cluster of ``workers`` single-threaded worker processes (default: one per core), closed on
    leaving. Raises ValueError naming the address (and where it came from) when it is not of the form
    ``tcp://HOST:PORT``, when nothing there accepts a connection within ``REACH_TIMEOUT_S`` (``check_reachable``, before
    Dask is imported), or when the scheduler does not answer within ``CONNECT_TIMEOUT_S``.

    The local workers start without ``WORKER_ENVIRONMENT_UNSET``. Workers of a cluster given by its address keep
    their own environment: started by ``dask worker`` they may run the odometry markedly slower (about 1.5 times in
    the one measurement noted at ``WORKER_ENVIRONMENT_UNSET``) unless started with ``--no-nanny`` or with a Dask config
    file that sets ``distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_`` to ``null``."""
    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        source = "--scheduler" if scheduler else "DASK_SCHEDULER_ADDRESS"
        check_reachable(address, source)
    import dask
    from distributed import Client, LocalCluster

    if address:
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT_S)
        except Exception as error:  # what answers there may be no Dask at all: its bytes read as a message's length
            raise ValueError(
                f"{source} {address}: something accepts connections there, but it did not answer as a Dask scheduler "
                f"within {CONNECT_TIMEOUT_S} s ({type(error).__name__}: {error}); give the address `dask scheduler` "
                "prints"
            ) from None
        with client:
            yield client
        return
    workers = workers or os.cpu_count() or 1
    unset = {f"distributed.nanny.pre-spawn-environ.{name}": None for name in WORKER_ENVIRONMENT_UNSET}
    with (
        dask.config.set(unset),
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
        ) as cluster, Client(cluster) as client,
    ):
        yield client


def check_reachable(address: str, source: str = "--scheduler") -> None:
    """A scheduler's ``address`` checked to be ``tcp://HOST:PORT`` (or another of Dask's protocols, left to Dask) and,
    for tcp, its host to accept a connection on the port within ``REACH_TIMEOUT_S``: a ValueError naming the address,
    ``source`` (the option or variable it came from) and what to do, in seconds rather than Dask's long wait."""
    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    if not rest or (scheme == "tcp" and not (host and port.isdigit())):
        raise ValueError(f"{source} {address}: expected a scheduler's address, tcp://HOST:PORT")
    if scheme != "tcp":
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=REACH_TIMEOUT_S).close()
    except OSError as error:
        why = f"no answer within {REACH_TIMEOUT_S:g} s" if isinstance(error, TimeoutError) else error.strerror
        raise ValueError(
            f"{source} {address}: no Dask scheduler there ({(why or str(error)).lower()}): start one "
            f"(`dask scheduler --port {port}` on {host}) and its workers, or leave out {source} for a cluster on this "
            "machine"
        ) from None


def add_cluster_arguments(parser) -> None:
    """``--scheduler`` and ``--workers`` on an ``argparse`` parser: the arguments of ``cluster_client``."""
    parser.add_argument(
        "--scheduler", help="a running Dask scheduler, tcp://HOST:PORT (default: DASK_SCHEDULER_ADDRESS, else local)"
    )
    parser.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
