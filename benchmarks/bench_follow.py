"""``palpbayes follow`` live: latency from a chunk's last sample to the printed decision.

Run: ``python benchmarks/bench_follow.py [--fast] [--chunk 100]``.  Streams the paper-like
3,840-sample palpation (800 Hz, 4.8 s) **in real time** (one sample every 1.25 ms, each line
written at its time; ``--fast``: as fast as the pipe takes them) into the stdin of a
``palpbayes follow --json`` subprocess, as a robot script would, and reads its stdout in a
thread.  The latency of an update is the time from writing the last sample of its chunk to
reading the printed update back from the pipe: the estimator, the formatting, and both pipes,
as the robot sees it.  A sample that reaches the max force or max depth ends its chunk, so the
stop lines of those runs are timed from that very sample.  Printed: median and max over the
updates in contact of a run that never stops (every chunk of the trace) and of one run per
stopping reason, the latency of each stop line, the ratio to the 1.25 ms sample interval (the
target: <= 10 ms, 8 samples, at 800 Hz on 2 cores), and the estimator's own update time on
the same chunks in this process, which is most of it.
"""

from __future__ import annotations

import argparse
import json
import os
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
RUNS = {"no stop (every update)": ["--max-force", "50"],
        # the statistical interval: the full one (follow's default) has the budget's floor
        "target precision 2 %": ["--target", "2%", "--target-on", "stat"],
        "max force 0.5 N": ["--max-force", "0.5"],
        "max depth 1 mm": ["--max-depth", "1e-3"]}


def stream(lines: list[str], rule: list[str], chunk: int, fast: bool):
    """Run follow on ``lines``; (latencies of the updates [s], which were in contact, the last
    update, the exit status)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "palpbayes", "follow", *TIP, "--json", "--chunk", str(chunk),
         *rule], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, bufsize=1, cwd=ROOT,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(
            [ROOT, *filter(None, [os.environ.get("PYTHONPATH")])])})
    proc.stderr.readline()  # the nu note: printed once imports are done, before reading
    sent = np.full(len(lines), np.nan)
    got: list[tuple[float, dict]] = []

    def read() -> None:
        for line in proc.stdout:
            if line.startswith("{"):
                row = json.loads(line)
                if row.get("event", "update") == "update":  # the last line: stop/end, checks
                    got.append((time.perf_counter(), row))

    reader = threading.Thread(target=read)
    reader.start()
    proc.stdin.write(lines[0])  # the header
    t0 = time.perf_counter()
    try:
        for k, line in enumerate(lines[1:]):
            if not fast:
                wait = t0 + (k + 1) * INTERVAL - time.perf_counter()
                if wait > 0:
                    time.sleep(wait)
            proc.stdin.write(line)
            proc.stdin.flush()
            sent[k] = time.perf_counter()
        proc.stdin.close()
    except BrokenPipeError:  # follow stopped and exited: the robot stops sending
        pass
    reader.join()
    rc = proc.wait()
    if not got:
        raise SystemExit(f"follow printed no update (exit {rc}): {proc.stderr.read()}")
    lat = np.array([t - sent[u["n"] - 1] for t, u in got])
    contact = np.array([u["in_contact"] for _, u in got])
    return lat, contact, got[-1][1], rc


def update_alone(tr, chunk: int) -> np.ndarray:
    """[s] The estimator's own update time per chunk of the whole trace in contact, in this
    process."""
    est = OnlineEstimator(ModelSpec(tr.tip, nu=0.3), rule=StoppingRule(max_force=50.0))
    times = []
    for t, z, f in chunks(tr, chunk):
        t0 = time.perf_counter()
        state = est.update(t, z, f)
        if state.in_contact:
            times.append(time.perf_counter() - t0)
    return np.array(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="no real-time pacing")
    ap.add_argument("--chunk", type=int, default=100)
    args = ap.parse_args()
    tr = paper_trace("paraboloid")
    lines = ["time_s,z_m,force_n\n"] + [f"{t:.10g},{z:.10g},{f:.10g}\n"
                                       for t, z, f in zip(tr.time, tr.z, tr.force, strict=True)]
    pace = "as fast as the pipe takes them" if args.fast else "in real time at 800 Hz"
    print(f"palpbayes follow: {tr.n_points} samples streamed {pace} through a pipe, chunk "
          f"{args.chunk}; latency = last sample of the chunk written -> update read back")
    print(f"{'run':<24} {'updates':>7} {'in contact: median':>19} {'max':>9} {'max/1.25ms':>10} "
          f"{'stop at n':>9} {'exit':>4}")
    for name, rule in RUNS.items():
        lat, contact, last, rc = stream(lines, rule, args.chunk, args.fast)
        c = lat[contact]  # before contact an update is cheap (no posterior yet)
        row = (f"{name:<24} {lat.size:>7} {np.median(c) * 1e3:>17.2f}ms {c.max() * 1e3:>7.2f}ms "
               f"{c.max() / INTERVAL:>10.1f}")
        if last["stop"]:  # the decision: the stop line's own latency
            print(f"{row} {last['n']:>9} {rc:>4}   (the stop: {lat[-1] * 1e3:.2f} ms = "
                  f"{lat[-1] / INTERVAL:.1f} samples)")
        else:
            print(f"{row} {'-':>9} {rc:>4}")
    own = update_alone(tr, args.chunk)
    print(f"{'estimator update alone':<24} {own.size:>7} {np.median(own) * 1e3:>17.2f}ms "
          f"{own.max() * 1e3:>7.2f}ms {own.max() / INTERVAL:>10.1f}   (in process, no I/O)")


if __name__ == "__main__":
    main()
