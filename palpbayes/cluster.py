"""Dask clients for fits on many cores or a cluster (``palpbayes map``, ``palpbayes fit
MANIFEST --scheduler``): a LocalCluster bound to loopback, or a scheduler at an address.

The LocalCluster listens on 127.0.0.1 only, with its HTTP server on a free port (distributed's
default, 8787 on every interface, collides with any other cluster or dashboard and exposes
the machine); a remote scheduler is reached at the address the user gives.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from .errors import InputError

if TYPE_CHECKING:
    from dask.distributed import Client

__all__ = ["CONNECT_TIMEOUT", "dask_client", "close_client"]

#: How long to wait for a remote Dask scheduler before giving up.
CONNECT_TIMEOUT = "20s"


def dask_client(scheduler: str | None = None, workers: int | None = None) -> Client:
    """A ``dask.distributed`` client: a new LocalCluster (``scheduler`` None or ``"local"``:
    ``workers`` single-threaded processes, default one per core) or the scheduler at an
    address.  The caller closes it (and its cluster) with ``client.close()``.

    The LocalCluster's worker processes end when this process dies, even killed: distributed
    gives each a pipe to its nanny (here, in this process) and ends it when the pipe closes
    (tests/integration/test_orphans.py)."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - dask is a dependency
        raise InputError("fits on a cluster need dask.distributed: "
                         "pip install 'dask[distributed]'") from exc
    if scheduler in (None, "local"):
        n = int(os.cpu_count() or 1) if workers is None else int(workers)
        if n < 1:
            raise InputError(f"workers {workers!r} must be at least 1")
        # loopback only, and the HTTP server on a free port: distributed's default (8787,
        # all interfaces) collides with any other cluster or dashboard on the machine
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address="127.0.0.1:0",
                               silence_logs=40)
        try:
            client = Client(cluster)
        except BaseException:
            cluster.close()
            raise
        client._palpbayes_cluster = cluster  # closed with the client below
        return client
    if workers is not None:
        raise InputError(f"workers = {workers!r} applies to the local cluster only; a cluster at "
                         f"{scheduler!r} has the workers it was started with")
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {scheduler!r} ({exc}); start it "
                         "with 'dask scheduler' and workers with 'dask worker ADDRESS', or "
                         "leave --scheduler out for a local cluster") from None


def close_client(client: Client) -> None:
    """Close a client made by :func:`dask_client` (and its LocalCluster)."""
    cluster = getattr(client, "_palpbayes_cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()
