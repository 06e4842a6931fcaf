"""``palpbayes follow`` live: latency from a sample sent to the printed decision.

Run: ``python benchmarks/bench_follow.py [--fast] [--chunk 100] [--repeat 5]
[--transport stdin,listen]``.  Streams the paper-like 3,840-sample palpation (800 Hz, 4.8 s)
**in real time** (one sample every 1.25 ms, each line written at its time; ``--fast``: as
fast as the transport takes them) to a ``palpbayes follow --json`` subprocess, as a robot
script would: into its stdin through a pipe (``stdin``), or over TCP loopback to
``follow --listen 0`` (``listen``; the sender sets ``TCP_NODELAY``, as a robot streaming
small lines should), and reads its stdout in a thread.

Printed, per transport:

* the **stop latency** of each stopping reason: from writing the sample the stop is at (the
  one that reached the max force or max depth; for a precision target, the last sample of the
  chunk whose update fired it) to reading back the first line that says the stop (a line with
  a non-empty ``stop``: the stop line, or with an older ``follow`` the update carrying it),
  median and range over ``--repeat`` runs, with the goal beside it (limits: <= 2 ms, answered
  before any posterior work; a target: <= 10 ms, the update it needs included);
* the latency of the updates in contact of a run that never stops (median and max), the
  estimator's own update time on the same chunks in this process, which is most of it.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
from common import paper_trace

from palpbayes.fitdata import ModelSpec
from palpbayes.online import OnlineEstimator, StoppingRule, chunks

#: The checkout this benchmark belongs to, ahead of any installed palpbayes.
ROOT = str(Path(__file__).resolve().parents[1])
RATE = 800.0
INTERVAL = 1 / RATE
TIP = ["--tip", "paraboloid", "--radius", "0.0117"]
#: The stopping runs: name -> (options, goal [s] of the stop latency).
STOPS = {"max force 0.5 N": (["--max-force", "0.5"], 2e-3),
         "max depth 1 mm": (["--max-depth", "1e-3"], 2e-3),
         # the statistical interval: the full one (follow's default) has the budget's floor
         "target 2 % (stat)": (["--target", "2%", "--target-on", "stat"], 10e-3)}
#: The run that never stops: every chunk of the trace is an update.
NO_STOP = ["--max-force", "50"]
TRANSPORTS = ("stdin", "listen")


def _start(rule: list[str], chunk: int, transport: str):
    """Start follow; (process, a function that sends one line, a function that closes)."""
    src = ["--listen", "0"] if transport == "listen" else []
    proc = subprocess.Popen(
        [sys.executable, "-m", "palpbayes", "follow", *TIP, "--json", "--chunk", str(chunk),
         *src, *rule], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, bufsize=1, cwd=ROOT,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [ROOT, *filter(None, [os.environ.get("PYTHONPATH")])])})
    proc.stderr.readline()  # the nu note: printed once imports are done, before reading
    if transport == "stdin":
        def send(line: str) -> None:
            proc.stdin.write(line)
            proc.stdin.flush()
        return proc, send, proc.stdin.close
    while True:  # "listening on HOST:PORT"
        note = proc.stderr.readline()
        if not note:
            raise SystemExit(f"follow --listen exited: {proc.stderr.read()}")
        if note.startswith("listening on "):
            host, _, port = note.split()[-1].rpartition(":")
            break
    conn = socket.create_connection((host, int(port)))
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    proc.stdin.close()

    def send_tcp(line: str) -> None:
        conn.sendall(line.encode())

    def close() -> None:
        try:
            conn.shutdown(socket.SHUT_WR)
        except OSError:
            pass
        conn.close()

    return proc, send_tcp, close


def stream(lines: list[str], rule: list[str], chunk: int, fast: bool, transport: str = "stdin"):
    """Run follow on ``lines``; (latencies of the updates [s], which were in contact, the
    first line that says the stop (None if none) with its latency [s], the exit status)."""
    proc, send, close = _start(rule, chunk, transport)
    sent = np.full(len(lines), np.nan)
    got: list[tuple[float, dict]] = []
    stop: list[tuple[float, dict]] = []

    def read() -> None:
        for line in proc.stdout:
            if line.startswith("{"):
                now = time.perf_counter()
                row = json.loads(line)
                if row.get("stop") and not stop:  # the first line that says the stop
                    stop.append((now, row))
                if row.get("event", "update") == "update":  # the last line: stop/end, checks
                    got.append((now, row))

    reader = threading.Thread(target=read)
    reader.start()
    send(lines[0])  # the header
    t0 = time.perf_counter()
    try:
        for k, line in enumerate(lines[1:]):
            if not fast:
                wait = t0 + (k + 1) * INTERVAL - time.perf_counter()
                if wait > 0:
                    time.sleep(wait)
            sent[k] = time.perf_counter()  # written from now
            send(line)
            if stop:  # the robot stops sending once told
                break
    except (BrokenPipeError, ConnectionError):  # follow stopped and exited
        pass
    close()
    reader.join()
    rc = proc.wait()
    if not got:
        raise SystemExit(f"follow printed no update (exit {rc}): {proc.stderr.read()}")
    lat = np.array([t - sent[u["n"] - 1] for t, u in got])
    contact = np.array([u["in_contact"] for _, u in got])
    said = None if not stop else (stop[0][1], stop[0][0] - sent[stop[0][1]["n"] - 1])
    return lat, contact, said, rc


def update_alone(tr, chunk: int) -> np.ndarray:
    """[s] The estimator's own update time per chunk of the whole trace in contact, in this
    process (as follow runs it: the full interval from 1,000 draws)."""
    from palpbayes.online.full_interval import SHOWN_BUDGET_DRAWS

    est = OnlineEstimator(ModelSpec(tr.tip, nu=0.3), rule=StoppingRule(max_force=50.0),
                          total=True, budget_draws=SHOWN_BUDGET_DRAWS)
    times = []
    for t, z, f in chunks(tr, chunk):
        t0 = time.perf_counter()
        state = est.update(t, z, f)
        if state.in_contact:
            times.append(time.perf_counter() - t0)
    return np.array(times)


def _ms(x: float) -> str:
    return f"{x * 1e3:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="no real-time pacing")
    ap.add_argument("--chunk", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=5, help="runs per stopping reason")
    ap.add_argument("--transport", default=",".join(TRANSPORTS),
                    help="comma-separated: stdin (a pipe), listen (TCP loopback)")
    args = ap.parse_args()
    transports = [t.strip() for t in args.transport.split(",") if t.strip()]
    if not set(transports) <= set(TRANSPORTS):
        raise SystemExit(f"--transport: one or more of {', '.join(TRANSPORTS)}")
    tr = paper_trace("paraboloid")
    lines = ["time_s,z_m,force_n\n"] + [f"{t:.10g},{z:.10g},{f:.10g}\n"
                                       for t, z, f in zip(tr.time, tr.z, tr.force, strict=True)]
    pace = "as fast as the transport takes them" if args.fast else "in real time at 800 Hz"
    print(f"palpbayes follow --json: {tr.n_points} samples streamed {pace}, chunk "
          f"{args.chunk}, {args.repeat} runs per stop; {os.cpu_count()} cores")
    print("stop latency: the sample the stop is at written -> the first line saying the stop "
          "read back [ms]")
    print(f"{'transport':<9} {'stop':<18} {'at n':>5} {'median':>7} {'range':>13} "
          f"{'goal':>6} {'samples':>7} {'exit':>4}")
    for transport in transports:
        for name, (rule, goal) in STOPS.items():
            lats, ns, rcs = [], set(), set()
            for _ in range(args.repeat):
                _, _, said, rc = stream(lines, rule, args.chunk, args.fast, transport)
                rcs.add(rc)
                if said is not None:
                    ns.add(said[0]["n"])
                    lats.append(said[1])
            if not lats:
                print(f"{transport:<9} {name:<18} {'-':>5}  never stopped (exit {rcs})")
                continue
            med = float(np.median(lats))
            ok = "ok" if med <= goal else "MISSED"
            print(f"{transport:<9} {name:<18} {','.join(map(str, sorted(ns))):>5} "
                  f"{_ms(med):>7} {_ms(min(lats)):>6}-{_ms(max(lats)):<6} "
                  f"{'<=' + _ms(goal)[:-3]:>6} {med / INTERVAL:>7.1f} "
                  f"{','.join(map(str, sorted(rcs))):>4}  {ok}")
    print("updates in contact of a run that never stops: chunk's last sample written -> "
          "update read back [ms]")
    for transport in transports:
        lat, contact, _, rc = stream(lines, NO_STOP, args.chunk, args.fast, transport)
        c = lat[contact]  # before contact an update is cheap (no posterior yet)
        print(f"{transport:<9} {'every update':<18} {c.size:>5} {_ms(np.median(c)):>7} "
              f"max {_ms(c.max()):<9} {'':>6} {np.median(c) / INTERVAL:>7.1f} {rc:>4}")
    own = update_alone(tr, args.chunk)
    print(f"{'in proc':<9} {'estimator update':<18} {own.size:>5} {_ms(np.median(own)):>7} "
          f"max {_ms(own.max()):<9} {'':>6} {np.median(own) / INTERVAL:>7.1f}       (no I/O)")


if __name__ == "__main__":
    main()
