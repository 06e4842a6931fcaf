"""A campaign or map killed with SIGKILL leaves no process behind (issue 46).

Each test starts the command in a process of its own, waits until its workers run, kills it
with SIGKILL (or interrupts it as Ctrl-C does) and checks that every process it had started
(pool workers, Dask workers, a fork server or resource tracker) ends within a few seconds.  A
process's children are read from ``/proc`` (Linux only).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pandas as pd
import pytest

from palpbayes.cli import main

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"),
    reason="finds a process's children in /proc/<pid>/task/*/children (Linux only)")

#: The shipped example campaign.
EXAMPLE = Path(__file__).resolve().parents[2] / "data" / "example-campaign"
#: How long a killed command's processes may take to end.
GRACE = 10.0
#: How long a command may take to start its workers (it reads and checks its traces first).
START = 180.0


def _children(pid: int) -> set[int]:
    """Ids of the live children of ``pid`` (none once it has ended)."""
    found: set[int] = set()
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return found
    for task in tasks:
        try:
            with open(f"/proc/{pid}/task/{task}/children") as f:
                found.update(int(x) for x in f.read().split())
        except OSError:
            pass
    return found


def _descendants(pid: int) -> set[int]:
    """Ids of every live process below ``pid``."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        kids = _children(todo.pop()) - found
        found |= kids
        todo.extend(kids)
    return found


def _identity(pid: int) -> tuple[str, str] | None:
    """(start time, state) of ``pid`` from /proc/<pid>/stat, None if there is no such process."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            stat = f.read()
    except OSError:
        return None
    fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) "
    return fields[19], fields[0]  # starttime (field 22), state (field 3)


def _cmdline(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _survivors(procs: dict[int, str]) -> dict[int, str]:
    """The processes of ``procs`` (pid -> start time) still running (a zombie, dead and
    waiting for init to reap it, is not)."""
    alive = {}
    for pid, start in procs.items():
        ident = _identity(pid)
        if ident is not None and ident[0] == start and ident[1] != "Z":
            alive[pid] = _cmdline(pid)
    return alive


def _default_sigint() -> None:
    """In the child before exec: SIGINT's default action (Python's KeyboardInterrupt)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def launch(tmp_path: Path) -> Iterator[Callable[..., subprocess.Popen]]:
    """Start ``python ARGS`` in ``tmp_path`` (output to a log file; ``session``: in a session
    and process group of its own); whatever it or its processes left running is killed at the
    end, so that a failing test leaves nothing behind."""
    started: list[subprocess.Popen] = []

    def start(*args: str, session: bool = False) -> subprocess.Popen:
        log = open(tmp_path / f"log{len(started)}.txt", "wb")  # noqa: SIM115 - closed below
        # SIGINT as a terminal gives it: a test run started in the background (a shell's '&'
        # without job control) ignores SIGINT, which its children would inherit, and Python
        # then installs no KeyboardInterrupt handler
        proc = subprocess.Popen([sys.executable, *args], cwd=tmp_path, stdin=subprocess.DEVNULL,
                                stdout=log, stderr=subprocess.STDOUT, start_new_session=session,
                                preexec_fn=_default_sigint)
        proc._log = log  # type: ignore[attr-defined]
        proc._seen = {}  # type: ignore[attr-defined]
        started.append(proc)
        return proc

    yield start
    for proc in started:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        proc._log.close()  # type: ignore[attr-defined]
        for pid in _survivors(proc._seen):  # type: ignore[attr-defined]
            os.kill(pid, signal.SIGKILL)


def _when_running(proc: subprocess.Popen, is_worker: Callable[[str], bool], n: int,
                  settle: float, ready: Path | None = None) -> dict[int, str]:
    """Wait until ``proc`` has ``n`` worker processes (``is_worker(cmdline)``) and the file
    ``ready`` (if given) exists, give them ``settle`` seconds to be at work and return every
    process it has started (pid -> start time)."""
    deadline = time.monotonic() + START
    seen: dict[int, str] = proc._seen  # type: ignore[attr-defined]

    def look() -> None:
        for pid in _descendants(proc.pid):
            ident = _identity(pid)
            if ident is not None:
                seen.setdefault(pid, ident[0])

    while True:
        assert proc.poll() is None, f"the command ended ({proc.returncode}) before its workers ran"
        look()
        workers = [cmd for cmd in _survivors(seen).values() if is_worker(cmd)]
        if len(workers) >= n and (ready is None or ready.exists()):
            break
        assert time.monotonic() < deadline, f"no {n} workers after {START} s: {seen}"
        time.sleep(0.2)
    time.sleep(settle)
    look()
    assert proc.poll() is None, "the command finished before it was stopped: make it longer"
    return dict(seen)


def _kill_when_running(proc: subprocess.Popen, is_worker: Callable[[str], bool], n: int,
                       settle: float, ready: Path | None = None) -> dict[int, str]:
    """:func:`_when_running`, then SIGKILL ``proc``."""
    procs = _when_running(proc, is_worker, n, settle, ready)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return procs


def _assert_all_end(procs: dict[int, str]) -> None:
    deadline = time.monotonic() + GRACE
    while (left := _survivors(procs)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not left, f"{len(left)} of {len(procs)} processes outlived their parent: {left}"


def _small_campaign(folder: Path) -> Path:
    """A manifest of three of the example campaign's traces (White, flat: ~30 s of fits on
    two workers, after ~10 s of reading and checking)."""
    rows = pd.read_csv(EXAMPLE / "manifest.csv").head(3)
    rows["file"] = [str(EXAMPLE / f) for f in rows["file"]]
    rows.to_csv(folder / "manifest.csv", index=False)
    return folder / "manifest.csv"


def _is_fit_worker(args: tuple[str, ...]) -> Callable[[str], bool]:
    """A pool worker of ``python ARGS``: forked (the same command line) or started by
    multiprocessing (spawn, fork server)."""
    command = " ".join(args)
    return lambda cmd: command in cmd or "multiprocessing" in cmd


def test_a_killed_campaign_leaves_no_worker(tmp_path, launch):
    """``palpbayes fit MANIFEST --workers 2``, SIGKILLed while its pool fits: both workers end
    (they used to wait for work forever, ~250 MB each)."""
    args = ("-m", "palpbayes", "fit", str(_small_campaign(tmp_path)), "--out",
            str(tmp_path / "res"), "--workers", "2", "--no-progress")
    proc = launch(*args)
    procs = _kill_when_running(proc, _is_fit_worker(args), n=2, settle=1.0)
    assert len(procs) >= 2
    _assert_all_end(procs)


def test_ctrl_c_stops_a_campaign_and_its_workers(tmp_path, launch):
    """Ctrl-C (SIGINT to the terminal's process group) while the pool fits: the command says
    it was interrupted, exits with status 130 and leaves no worker."""
    args = ("-m", "palpbayes", "fit", str(_small_campaign(tmp_path)), "--out",
            str(tmp_path / "res"), "--workers", "2", "--no-progress")
    proc = launch(*args, session=True)
    procs = _when_running(proc, _is_fit_worker(args), n=2, settle=1.0)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=120) == 130
    assert "interrupted" in (tmp_path / "log0.txt").read_text()
    _assert_all_end(procs)


def test_a_killed_map_leaves_no_dask_process(tmp_path, launch):
    """``palpbayes map --workers 2`` (a Dask LocalCluster), SIGKILLed while it fits: its worker
    processes and the resource tracker end (distributed's parent pipe; the nannies run in the
    parent)."""
    rc = main(["simulate", str(tmp_path / "block"), "--map", "--grid", "9x9", "--step", "3e-3",
               "--lump-ratio", "20", "--lump-radius", "5e-3", "--lump-depth", "5.5e-3",
               "--lump-x", "12.5e-3", "--lump-y", "11.2e-3", "--seed", "4"])
    assert rc == 0
    proc = launch("-m", "palpbayes", "map", str(tmp_path / "block" / "manifest.csv"), "--out",
                  str(tmp_path / "map"), "--workers", "2", "--no-progress")
    procs = _kill_when_running(proc, lambda cmd: "spawn_main" in cmd, n=2, settle=3.0)
    assert len(procs) >= 2
    _assert_all_end(procs)


# A pool with each start method: the fork server is what fit_campaign uses on Python >= 3.12
# and macOS, fork on Linux before 3.12; spawn takes the Linux death signal as fork does.
_POOL = """
import concurrent.futures as cf, multiprocessing as mp, sys, time
from palpbayes.procs import lifeline
if __name__ == "__main__":
    ctx = mp.get_context(sys.argv[1])
    pool = cf.ProcessPoolExecutor(2, mp_context=ctx, **lifeline(ctx))
    list(pool.map(time.sleep, [0.5, 0.5]))  # the workers came through the initializer
    pool.submit(time.sleep, 600)
    pool.submit(time.sleep, 600)
    open("ready", "w").close()
    time.sleep(600)
"""


@pytest.mark.parametrize("method", ["fork", "forkserver", "spawn"])
def test_a_pool_with_a_lifeline_ends_with_its_parent(tmp_path, launch, method):
    """:func:`palpbayes.procs.lifeline`: the workers of a SIGKILLed pool's parent end, and with
    them its fork server and resource tracker."""
    (tmp_path / "pool.py").write_text(_POOL)
    proc = launch("pool.py", method)
    procs = _kill_when_running(proc, lambda cmd: "pool.py" in cmd or "multiprocessing" in cmd,
                               n=2, settle=1.0, ready=tmp_path / "ready")
    _assert_all_end(procs)
