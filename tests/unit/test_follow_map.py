"""``palpbayes follow --listen PORT --map DIR``: the live loop of an active search, one
connection per press, on loopback with a simulated robot (a real ``python -m palpbayes``
process, so that the exit status and stderr are the command's)."""

from __future__ import annotations

import json
import math
import queue
import socket
import subprocess
import sys
import threading
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.bayes.mixture import MixtureSummary
from palpbayes.cli import main
from palpbayes.cli.follow_map import parse_press_line, press_posterior
from palpbayes.cli.next import EXIT_UNDECIDED
from palpbayes.errors import InputError
from palpbayes.inclusion import Inclusion
from palpbayes.online import OnlineState
from palpbayes.sim.phantom import MapPhantom

ROOT = Path(__file__).resolve().parents[2]
TIP = ["--tip", "paraboloid", "--radius", "0.0117"]
PHANTOM = MapPhantom(inclusion=Inclusion(x=0.02, y=0.024, depth=0.006, radius=0.005, ratio=10),
                     seed=1)
#: follow's stop [m], above the phantom's 2 mm presses so that the stop line comes mid-press.
MAX_DEPTH = 0.0015
BUDGET = 3
#: A wait that only a bug makes long [s].
PATIENCE = 30.0


def _init(folder: Path) -> None:
    assert main(["next", str(folder), "--init", "--footprint", "0,0.042,0,0.042",
                 "--thickness", "0.02", *TIP, "--depth", "0.002"]) == 0


class Follow:
    """``palpbayes follow --listen 0 --map DIR`` as a process: its port, stdout, stderr."""

    def __init__(self, folder: Path, *extra: str) -> None:
        cmd = [sys.executable, "-m", "palpbayes", "follow", "--listen", "0", "--map",
               str(folder), *TIP, "--nu", str(PHANTOM.nu), "--json", *extra]
        self.proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        self.err: list[str] = []
        self.out: list[str] = []
        ports: queue.Queue = queue.Queue()

        def read_err() -> None:
            for line in self.proc.stderr:
                self.err.append(line)
                if line.startswith("listening on "):
                    ports.put(int(line.rsplit(":", 1)[1]))
            ports.put(None)

        def read_out() -> None:
            self.out.extend(self.proc.stdout)

        self.threads = [threading.Thread(target=f, daemon=True) for f in (read_err, read_out)]
        for t in self.threads:
            t.start()
        self.port = ports.get(timeout=PATIENCE)
        assert self.port is not None, "".join(self.err)

    def wait(self) -> int:
        rc = self.proc.wait(timeout=PATIENCE)
        for t in self.threads:
            t.join(PATIENCE)
        return rc

    def kill(self) -> None:
        """Kill the process if it still runs (a failed test), and close its pipes."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(PATIENCE)
        for t in self.threads:
            t.join(PATIENCE)
        self.proc.stdout.close()
        self.proc.stderr.close()


def _samples(trace, upto: int | None = None) -> list[str]:
    return [f"{float(t)!r},{float(z)!r},{float(f)!r}\n"
            for t, z, f in list(zip(trace.time, trace.z, trace.force, strict=True))[:upto]]


class Received:
    """The lines a socket receives, one at a time (:meth:`next`), as JSON."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock, self.buf, self.eof = sock, b"", False

    def _recv(self) -> None:
        data = self.sock.recv(65536)
        self.eof = not data
        self.buf += data

    def next(self) -> dict:
        while b"\n" not in self.buf:
            assert not self.eof, f"the connection ended with {self.buf!r}"
            self._recv()
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)


def press(port: int, x: float, y: float, rows: list[str], *, stop_on_stop_line: bool,
          half_close: bool = True) -> tuple[list[dict], int]:
    """A robot's press: connect, ``press X Y``, the samples (all at once, or a chunk at a
    time, each after follow's update on the one before, until the stop line), then read
    every line until the answer; the lines received and the samples sent."""
    got: list[dict] = []
    sent = 0
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE) as s:
        received = Received(s)
        s.sendall(f"press {x!r} {y!r}\ntime_s,z_m,force_n\n".encode())
        block = 100 if stop_on_stop_line else len(rows)
        for i in range(0, len(rows), block):
            s.sendall("".join(rows[i:i + block]).encode())
            sent = min(len(rows), i + block)
            if not stop_on_stop_line:
                continue
            while True:  # the robot moves on once follow has judged what it sent
                got.append(received.next())
                if got[-1]["event"] == "stop" or got[-1].get("n", 0) >= sent:
                    break
            if got[-1]["event"] == "stop":  # the stop line: stop the motion
                assert got[-1]["final"] is False
                break
        if half_close:
            s.shutdown(socket.SHUT_WR)
        while not got or "decision" not in got[-1]:
            got.append(received.next())
    return got, sent


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """Four connections: a press that keeps sending after its stop line and never shuts its
    side, a press without contact, a press that stops on its stop line, and the press that
    spends the budget of three."""
    folder = tmp_path_factory.mktemp("live") / "search"
    _init(folder)
    follow = Follow(folder, "--max-depth", str(MAX_DEPTH), "--budget", str(BUDGET))
    conns, csv_rows, sent_rows = [], [], []
    try:
        x, y = 0.022, 0.022  # the first press of 'palpbayes next' on this footprint
        for key, how in enumerate(("after_stop", "no_contact", "stop", "stop"), start=1):
            trace = PHANTOM.press(x, y, key=key)
            if how == "no_contact":  # the approach only, then the robot shuts its side
                got, sent = press(follow.port, x, y, _samples(trace, 200),
                                  stop_on_stop_line=False)
            elif how == "after_stop":  # every sample, no half-close: the answer must come
                got, sent = press(follow.port, x, y, _samples(trace), stop_on_stop_line=False,
                                  half_close=False)
            else:
                got, sent = press(follow.port, x, y, _samples(trace), stop_on_stop_line=True)
            conns.append((x, y, how, got))
            sent_rows.append((sent, trace.n_points))
            csv_rows.append(len(pd.read_csv(folder / "presses.csv")))
            answer = got[-1]
            if answer["event"] == "next":
                x, y = answer["presses"][0]["x_m"], answer["presses"][0]["y_m"]
        rc = follow.wait()
    finally:
        follow.kill()
    return {"folder": folder, "conns": conns, "rows": csv_rows, "rc": rc, "sent": sent_rows,
            "out": follow.out, "err": "".join(follow.err)}


def test_every_press_is_answered_on_its_connection(session):
    events = [[r["event"] for r in got] for _, _, _, got in session["conns"]]
    assert [e[-1] for e in events] == ["next", "next", "next", "done"]
    for (x, y, how, got), ev in zip(session["conns"], events, strict=True):
        assert "decision" in got[-1] and "decision" not in got[-2]
        # the press is accepted before its samples are read, at the search's depth
        assert got[0] == {"event": "accepted", "x_m": x, "y_m": y, "depth_m": 0.002,
                          "max_force_n": None, "predicted_force_n": None}
        if how == "no_contact":
            assert got[-2]["event"] == "end" and not got[-2]["in_contact"]
            assert "stop" not in ev[:-1]
            continue
        # line numbers are the connection's: 'press X Y' is line 1, the header line 2
        assert (got[1]["event"], got[1]["n"], got[1]["line"]) == ("update", 100, 102)
        # the stop line, the update up to it, the last line, then the answer
        assert ev.count("update") >= 10 and ev[-4:-1] == ["stop", "update", "stop"]
        assert (got[-4]["final"], got[-4]["stop"], got[-2]["final"]) == (
            False, "max depth", True)
        assert got[-3]["stop"] == "max depth" and got[-3]["E_pa"] > 0
    # the robot that stops on the stop line sends fewer samples than its trace has; the
    # stop is at a sample it sent
    for (_, _, how, got), (sent, n) in zip(session["conns"], session["sent"], strict=True):
        if how == "stop":
            assert got[-4]["n"] <= sent < n - 100


def test_the_socket_carries_every_line_stdout_does(session):
    sent = [json.loads(ln) for ln in session["out"]]
    assert sent == [r for _, _, _, got in session["conns"] for r in got]


def test_each_press_with_an_estimate_adds_one_row(session):
    assert session["rows"] == [1, 1, 2, 3]  # the press without contact adds none
    no_contact = session["conns"][1][3][-1]
    assert "no contact" in no_contact["warning"] and no_contact["n"] == 1
    assert all("warning" not in got[-1] for i, (*_, got) in enumerate(session["conns"])
               if i != 1)
    df = pd.read_csv(session["folder"] / "presses.csv")
    assert list(df.columns) == ["x_m", "y_m", "logE_mean", "logE_sd", "p_lump"]
    added = [c for c in session["conns"] if c[2] != "no_contact"]
    assert np.allclose(df[["x_m", "y_m"]], [(x, y) for x, y, _, _ in added], atol=1e-12)
    # the press's E is the phantom's at that point, up to its heterogeneity
    expect = np.log(PHANTOM.apparent_modulus(df["x_m"], df["y_m"]))
    sd = df["logE_sd"].to_numpy()
    assert np.isfinite(df[["logE_mean", "logE_sd"]].to_numpy()).all() and (sd > 0).all()
    assert (sd < 0.05).all()
    tol = 4 * np.hypot(sd, PHANTOM.heterogeneity)
    assert (np.abs(df["logE_mean"] - expect) < tol).all(), (df["logE_mean"] - expect, tol)
    # P(lump) after each press, as its answer said
    p = df["p_lump"].to_numpy()
    assert ((p >= 0) & (p <= 1)).all()
    assert np.allclose(p, [got[-1]["p_lump"] for *_, got in added])
    assert [got[-1]["n"] for *_, got in added] == [1, 2, 3]


def test_the_budget_stops_undecided_without_a_traceback(session):
    assert session["rc"] == EXIT_UNDECIDED == 11, session["err"]
    last = session["conns"][-1][3][-1]
    assert (last["event"], last["decision"], last["presses"]) == ("done", "", [])
    assert f"budget of {BUDGET} presses" in last["reason"]
    assert "search stopped: undecided" in session["err"]
    assert "Traceback" not in session["err"] and "Exception" not in session["err"]


def test_a_connection_without_a_press_line_gets_an_error(tmp_path):
    _init(tmp_path / "s")
    follow = Follow(tmp_path / "s", "--max-depth", "0.002")
    try:
        with socket.create_connection(("127.0.0.1", follow.port), timeout=PATIENCE) as s:
            s.sendall(b"\ntime_s,z_m,force_n\n0.1,0.1,0.0\n")
            s.shutdown(socket.SHUT_WR)
            lines = s.makefile("r", encoding="utf-8").read().splitlines()
        rc = follow.wait()
    finally:
        follow.kill()
    assert len(lines) == 1
    error = json.loads(lines[0])
    assert error["event"] == "error"
    assert "line 2: 'time_s,z_m,force_n' is not a press line" in error["message"]
    assert "send 'press X Y'" in error["message"]
    err = "".join(follow.err)
    assert rc == 2 and f"palpbayes follow: error: {error['message']}" in err
    assert "Traceback" not in err
    assert follow.out == [] and len(pd.read_csv(tmp_path / "s" / "presses.csv")) == 0


def test_map_needs_listen_and_its_options_need_map(tmp_path, capsys):
    _init(tmp_path / "s")
    assert main(["follow", *TIP, "--max-depth", "0.002", "--map", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert "--map" in err and "needs --listen" in err
    assert main(["follow", *TIP, "--max-depth", "0.002", "--budget", "3"]) == 2
    assert "--budget belong(s) to the live loop: give --map DIR" in capsys.readouterr().err


def test_a_folder_without_a_state_is_named_before_listening(tmp_path, capsys):
    empty = tmp_path / "nothing"
    empty.mkdir()
    rc = main(["follow", *TIP, "--max-depth", "0.002", "--listen", "0", "--map", str(empty)])
    err = capsys.readouterr().err
    assert rc == 2
    assert f"palpbayes follow: error: {empty}: holds no search state" in err
    assert "palpbayes next DIR --init" in err and "listening on" not in err


@pytest.mark.parametrize("line, words", [
    ("", "ended before its first line"),
    ("press 0.01\n", "'press 0.01' is not a press line"),
    ("press 0.01 0.02 0.002 5\n", "is not a press line"),
    ("press 0.01 0.02 inf\n", "must be finite"),
    ("press 1e-3 0x10\n", "is not a press line"),
    ("PRESS nan 0.01\n", "must be finite"),
    ("move 0.01 0.02\n", "'move 0.01 0.02' is not a press line"),
])
def test_a_press_line_is_two_numbers(line, words):
    with pytest.raises(InputError) as info:
        parse_press_line(line, "tcp here", 3)
    assert words in str(info.value) and "send 'press X Y'" in str(info.value)


def test_a_press_line():
    assert parse_press_line("  press 0.02  2.4e-2 \n", "tcp here", 1) == (0.02, 0.024, None)
    assert parse_press_line("press 0.02 0.024 2e-3\n", "tcp here", 1) == (0.02, 0.024, 0.002)


def test_the_press_posterior_is_the_log_of_the_statistical_interval():
    E = MixtureSummary(mean=5.1e4, sd=1e3, median=5e4, lo=4.8e4, hi=5.3e4, level=0.9)
    total = MixtureSummary(mean=5.1e4, sd=3e3, median=5e4, lo=4e4, hi=6e4, level=0.9)
    state = OnlineState(n=10, t=1.0, z=0.1, in_contact=True, n_contact=5, depth=1e-3,
                        peak_force=0.1, E=E, z_surf=None, stop="", E_total=total)
    mean, sd = press_posterior(state)
    assert mean == math.log(5e4)
    assert sd == pytest.approx((math.log(5.3e4) - math.log(4.8e4)) / (2 * 1.6448536),
                               rel=1e-7)
    assert press_posterior(None) is None
    assert press_posterior(replace(state, in_contact=False, E=None)) is None
    assert press_posterior(replace(state, E=replace(E, lo=0.0))) is None


def test_a_search_already_stopped_is_said_without_listening(tmp_path, capsys):
    from palpbayes.active.files import append_press, read_state

    _init(tmp_path / "s")
    append_press(tmp_path / "s", read_state(tmp_path / "s"), 0.022, 0.022, math.log(5e4), 0.01)
    capsys.readouterr()
    rc = main(["follow", *TIP, "--max-depth", "0.002", "--listen", "0", "--map",
               str(tmp_path / "s"), "--budget", "1"])
    out = capsys.readouterr()
    assert rc == EXIT_UNDECIDED
    answer = json.loads(out.out)
    assert (answer["event"], answer["n"]) == ("done", 1) and "budget of 1" in answer["reason"]
    assert "has already stopped" in out.err and "listening on" not in out.err
