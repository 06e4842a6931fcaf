"""A simulated robot finds a lump with ``palpbayes follow --listen 0 --map DIR``.

The robot here is a plain socket client: for each press it connects, sends ``press X Y``,
waits for the ``"accepted"`` line (a refused press gets ``"refused"`` and is not made), sends
the press's samples (CSV lines, from a simulated phantom with a hard lump), stops
sending when it reads the stop line back, shuts its sending side, reads lines until the
answer (the JSON line with a ``"decision"`` key) and moves to the press it names, until the
answer's ``"event"`` is ``"done"``.  A real robot does the same with its own samples.

Run it from the repository (it starts ``python -m palpbayes``)::

    python examples/robot_search.py              # budget of 40 presses
    python examples/robot_search.py --budget 10
    python examples/robot_search.py --depths 0.1,0.2   # the search chooses each press's depth

It prints one line per press (n, x, y, P(lump) after it, how the press ended) and the
decision; follow's own output goes to ``follow.log`` in the temporary search folder.
"""

from __future__ import annotations

import argparse
import json
import math
import select
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from palpbayes.inclusion import Inclusion
from palpbayes.sim.phantom import MapPhantom

#: The phantom: a 20 mm block, E = 50 kPa, with a lump ten times as stiff, 5 mm in radius,
#: its centre 6 mm deep at (20, 24) mm.
PHANTOM = MapPhantom(inclusion=Inclusion(x=0.02, y=0.024, depth=0.006, radius=0.005, ratio=10),
                     seed=1)
TIP = ["--tip", "paraboloid", "--radius", "0.0117"]  # the paper's paraboloid tip
DEPTH = 0.002  # [m] indentation of every press
FOOTPRINT = "0,0.042,0,0.042"  # [m] x0,x1,y0,y1: where to press and where the lump may be
BLOCK = 50  # samples sent between two looks at what came back


def palpbayes(*args: str) -> list[str]:
    """The command line of ``palpbayes ARGS`` with this Python."""
    return [sys.executable, "-m", "palpbayes", *args]


def start_follow(folder: Path, budget: int, max_depth: float,
                 log) -> tuple[subprocess.Popen, int]:
    """Start the live loop on a free loopback port; the process and its port."""
    cmd = palpbayes("follow", "--listen", "0", "--map", str(folder), *TIP,
                    "--nu", str(PHANTOM.nu), "--json", "--max-depth", str(max_depth),
                    "--budget", str(budget))
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:  # 'listening on 127.0.0.1:PORT' once it is ready
        log.write(line)
        if line.startswith("listening on "):
            port = int(line.rsplit(":", 1)[1])
            break
    else:
        raise SystemExit(f"follow did not start (exit status {proc.wait()}); see {log.name}")

    def keep_stderr() -> None:  # follow's notes, into the log (a full pipe would block it)
        for line in proc.stderr:
            log.write(line)
            log.flush()

    threading.Thread(target=keep_stderr, daemon=True).start()
    return proc, port


def _json(line: str) -> dict | None:
    try:
        row = json.loads(line)
    except ValueError:
        return None
    return row if isinstance(row, dict) else None


def press(port: int, x: float, y: float, key: int, speed: float,
          depth: float = DEPTH) -> tuple[dict, bool]:
    """One press at (x, y) [m] to ``depth`` [m], its samples sent at ``speed`` times their
    own pace: the answer, and whether the press ended on the stop line."""
    trace = PHANTOM.press(x, y, key=key, depth=depth)
    start = time.perf_counter()
    rows = [f"{float(t)!r},{float(z)!r},{float(f)!r}\n"
            for t, z, f in zip(trace.time, trace.z, trace.force, strict=True)]
    got, stopped = [], False
    with socket.create_connection(("127.0.0.1", port), timeout=60) as s:
        reader = s.makefile("r", encoding="utf-8")
        s.sendall(f"press {x!r} {y!r} {depth!r}\n".encode())
        verdict = _json(reader.readline()) or {}  # accepted or refused, before any motion
        if verdict.get("event") != "accepted":
            raise SystemExit(f"follow did not accept the press: {verdict.get('message')}")
        s.sendall(b"time_s,z_m,force_n\n")
        for i in range(0, len(rows), BLOCK):
            if speed > 0:  # the robot moves at its own pace: wait for the samples' time
                ahead = trace.time[i] / speed - (time.perf_counter() - start)
                time.sleep(max(0.0, ahead))
            s.sendall("".join(rows[i:i + BLOCK]).encode())
            while select.select([s], [], [], 0)[0]:  # what came back so far
                line = reader.readline()
                if not line:
                    break
                row = _json(line)
                got.append(row)
                if row and row.get("event") == "stop" and row.get("final") is False:
                    stopped = True  # the stop line: stop the motion
                    break
            if stopped:
                break
        s.shutdown(socket.SHUT_WR)  # no more samples
        for line in reader:  # the rest of follow's lines, then the answer
            row = _json(line)
            if row and "decision" in row:
                return row, stopped
        raise SystemExit("follow closed the connection without an answer")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=int, default=40, help="most presses (default 40)")
    ap.add_argument("--speed", type=float, default=0.0,
                    help="send the samples at this many times their real pace (default 0: "
                         "as fast as the socket takes them)")
    ap.add_argument("--max-depth", type=float, default=DEPTH,
                    help=f"follow's stop [m] (default {DEPTH}, the depth of the simulated "
                         "presses, so the stop line comes at their last sample if at all; "
                         "try 0.0015 with --speed 4 to see it stop the motion)")
    ap.add_argument("--depths", default=None, metavar="F1,F2",
                    help="press depths as fractions of the thickness (e.g. 0.1,0.2): the "
                         "search chooses each press's depth by information per second")
    args = ap.parse_args(argv)
    depths = ([] if args.depths is None else ["--depths", args.depths])
    deepest = max([DEPTH] + [float(f) * PHANTOM.thickness
                             for f in (args.depths or "").split(",") if f])
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="robot_search_") as tmp:
        folder = Path(tmp) / "search"
        subprocess.run(palpbayes("next", str(folder), "--init", "--footprint", FOOTPRINT,
                                 "--thickness", str(PHANTOM.thickness), *TIP,
                                 "--depth", str(DEPTH), *depths), check=True,
                       stdout=subprocess.DEVNULL)
        first = subprocess.run(palpbayes("next", str(folder), "--json"), capture_output=True,
                               text=True)
        answer = json.loads(first.stdout)
        with open(Path(tmp) / "follow.log", "w") as log:
            proc, port = start_follow(folder, args.budget,
                                      max(args.max_depth, deepest) if depths else
                                      args.max_depth, log)
            print(f"follow listens on 127.0.0.1:{port}; the lump is at (20.0, 24.0) mm")
            print("  n  x [mm]  y [mm]  depth [mm]  P(lump)  press ended on")
            n = 0
            try:
                while answer["event"] == "next":
                    p = answer["presses"][0]
                    n += 1
                    d = p.get("depth_m") or DEPTH
                    answer, stopped = press(port, p["x_m"], p["y_m"], key=n, speed=args.speed,
                                            depth=d)
                    how = "the stop line" if stopped else "the trace's end"
                    warn = f"  ({answer['warning']})" if "warning" in answer else ""
                    print(f"{n:3d}  {1e3 * p['x_m']:6.1f}  {1e3 * p['y_m']:6.1f}  "
                          f"{1e3 * d:10.1f}  {answer['p_lump']:7.3f}  {how}{warn}", flush=True)
                status = proc.wait(timeout=60)
            finally:
                if proc.poll() is None:
                    proc.kill()
    what = answer["decision"] or "undecided"
    print(f"decision: {what} ({answer['reason']}); follow exited with status {status}")
    if answer["decision"] == "lump":
        err = 1e3 * math.hypot(answer["x_m"] - 0.02, answer["y_m"] - 0.024)
        print(f"lump centre ({1e3 * answer['x_m']:.1f}, {1e3 * answer['y_m']:.1f}) mm, "
              f"{err:.1f} mm from the true one; 90 % radius "
              f"{1e3 * answer['centre_radius_m']:.1f} mm")
    print(f"{n} presses in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
