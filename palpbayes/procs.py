"""Worker processes that end when the process that started them dies.

A process pool's workers outlive a parent that is killed (``kill -9``, the out-of-memory
killer, a batch system ending the job): nothing closes their task queue, so each waits for
work forever, holding its memory (issue 46: two ~250 MB workers per SIGKILLed campaign).
:func:`lifeline` gives a :class:`concurrent.futures.ProcessPoolExecutor` the worker
initializer :func:`die_with_parent` that ties each worker's life to the pool's parent::

    ctx = multiprocessing.get_context("fork")
    pool = ProcessPoolExecutor(max_workers=2, mp_context=ctx, **lifeline(ctx))

On Linux, with the ``fork`` and ``spawn`` start methods, the kernel does it:
``prctl(PR_SET_PDEATHSIG, SIGKILL)`` kills the worker as soon as its parent exits, whatever
the worker is doing (even inside compiled code holding the GIL).  The parent may die between
the worker's start and that call; the initializer then finds itself re-parented and exits.

Otherwise (the ``forkserver`` start method, which :mod:`palpbayes.campaign.run` uses from
Python 3.12 and on macOS; Windows) a daemon thread waits on the pipe (handle) to the parent that
:mod:`multiprocessing` gives every child and ends the worker when it closes.  A fork server's
worker is the server's child, not the parent's, and the server lives as long as any of its
workers: a death signal tied to it would never come.

The Dask LocalCluster of :mod:`palpbayes.cluster` needs none of this: ``distributed`` starts
each worker with such a pipe to the process that holds the cluster.
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
from typing import Any

__all__ = ["die_with_parent", "lifeline"]

#: ``PR_SET_PDEATHSIG`` of <linux/prctl.h>: the signal a process gets when its parent dies.
_PR_SET_PDEATHSIG = 1

#: Exit status of a worker that ends because its parent is gone.
_ORPHAN_EXIT = 1


def lifeline(ctx: multiprocessing.context.BaseContext) -> dict[str, Any]:
    """``initializer`` and ``initargs`` for a process pool started with ``ctx``, so that its
    workers end when this process dies.

    Parameters
    ----------
    ctx
        The pool's multiprocessing context (its ``mp_context``).

    Returns
    -------
    dict
        Keyword arguments for :class:`concurrent.futures.ProcessPoolExecutor`:
        :func:`die_with_parent` with this process's id and ``ctx``'s start method.
    """
    return {"initializer": die_with_parent,
            "initargs": (os.getpid(), ctx.get_start_method())}


def die_with_parent(parent_pid: int, start_method: str) -> None:
    """Worker initializer: end this process when the process ``parent_pid`` that started the
    pool dies (see :func:`lifeline`).

    Parameters
    ----------
    parent_pid
        Id of the process that made the pool.
    start_method
        The pool's start method (``"fork"``, ``"spawn"`` or ``"forkserver"``).

    Notes
    -----
    On Linux the death signal is tied to the parent *thread* that started the worker: a pool
    must be made and used in a thread that outlives it (as :func:`palpbayes.fit_campaign`
    does).  The thread that ends a worker elsewhere needs the GIL: a worker inside compiled
    code that holds it ends when that call returns.
    """
    if sys.platform.startswith("linux") and start_method != "forkserver":
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0:
            err = ctypes.get_errno()
            raise OSError(err, f"prctl(PR_SET_PDEATHSIG): {os.strerror(err)}")
        # a child of parent_pid, re-parented (to init or a subreaper) if it died before prctl
        if os.getppid() != parent_pid:
            os._exit(_ORPHAN_EXIT)
        return
    parent = multiprocessing.parent_process()
    if parent is not None:
        threading.Thread(target=_exit_when_closed, args=(parent.sentinel,), daemon=True,
                         name="palpbayes-lifeline").start()


def _exit_when_closed(sentinel: Any) -> None:
    """Wait until ``sentinel`` (the parent's pipe or process handle) is ready, i.e. the
    parent has died, then end this process at once."""
    multiprocessing.connection.wait([sentinel])
    os._exit(_ORPHAN_EXIT)
