"""The live loop refuses unsafe presses (issue 60): a press off the footprint, in a keep-out
zone, at a depth not allowed or over the predicted force limit gets one ``refused`` line and
is not recorded; a press whose measured force reaches the limit is stopped and not recorded;
a robot that stops reading loses its press; each time the next press is still accepted.  The
checks themselves (:mod:`palpbayes.active.safety`) without a socket first."""

from __future__ import annotations

import json
import math
import socket
import threading
import time
from argparse import Namespace

import numpy as np
import pandas as pd
import pytest

from palpbayes.active.files import read_limits
from palpbayes.active.safety import (
    DEPTH_TOLERANCE,
    UPPER_Z,
    PressLimits,
    check_depth,
    check_force,
    check_position,
    check_press,
    parse_depths,
    plausible_modulus,
)
from palpbayes.bayes.mixture import MixtureSummary
from palpbayes.cli import follow_map, main
from palpbayes.cli.next import EXIT_UNDECIDED
from palpbayes.errors import InputError
from palpbayes.online import OnlineState
from palpbayes.online.tcp import accept_session, listen
from tests.unit.test_follow_map import PATIENCE, PHANTOM, TIP, Follow, Received, _samples

FOOTPRINT = (0.0, 0.042, 0.0, 0.042)
KEEP = ((0.03, 0.01, 0.004),)
H = 0.02
LIMITS = PressLimits(depths=(0.1, 0.2), max_force=4.0, depth=0.002)


def hertz(E: float, d: float) -> float:
    """The paraboloid of the tests (R 11.7 mm, nu 0.3) [N]."""
    return 4 / 3 * E / (1 - 0.3 ** 2) * math.sqrt(0.0117) * d ** 1.5


# -- the checks, without a socket ------------------------------------------------------------

def test_a_press_off_the_footprint_is_refused_with_its_bounds():
    r = check_position(FOOTPRINT, KEEP, 0.05, 0.01)
    assert r.rule == "footprint"
    assert "press at (0.05, 0.01) m is off the footprint x 0 to 0.042 m, y 0 to 0.042 m" in (
        r.message)
    assert "not recorded" in r.message and "press inside it" in r.message
    assert check_position(FOOTPRINT, KEEP, 0.0, 0.042) is None  # the edges may be pressed
    assert check_position(FOOTPRINT, KEEP, 0.021, -1e-6).rule == "footprint"


def test_a_press_in_a_keep_out_zone_is_refused_naming_the_zone():
    zones = ((0.01, 0.01, 0.002), *KEEP)
    r = check_position(FOOTPRINT, zones, 0.031, 0.012)
    assert r.rule == "keep-out"
    assert "inside keep-out zone 2 (centre (0.03, 0.01) m, radius 0.004 m" in r.message
    assert "press outside it" in r.message
    assert check_position(FOOTPRINT, zones, 0.0339, 0.01).rule == "keep-out"
    assert check_position(FOOTPRINT, zones, 0.0341, 0.01) is None


def test_only_an_allowed_depth_may_be_pressed():
    assert check_depth(LIMITS, H, 0.02, 0.02, 0.002) is None
    assert check_depth(LIMITS, H, 0.02, 0.02, 0.004 + 0.5 * DEPTH_TOLERANCE) is None
    assert check_depth(LIMITS, H, 0.02, 0.02, None) is None  # the search's depth, allowed
    r = check_depth(LIMITS, H, 0.02, 0.02, 0.003)
    assert r.rule == "depth" and "depth 0.003 m: the depth is not an allowed depth" in (
        r.message)
    assert "0.002 m (0.1 of 0.02 m), 0.004 m (0.2 of 0.02 m)" in r.message
    r = check_depth(PressLimits(depths=(0.2,), depth=0.002), H, 0.02, 0.02, None)
    assert "gives no depth, and the search's depth 0.002 m is not an allowed depth" in (
        r.message) and "press X Y DEPTH" in r.message
    # without a depth set any depth inside the block goes, nothing outside it
    assert check_depth(PressLimits(), H, 0.02, 0.02, 0.01) is None
    for bad in (0.0, -0.001, 0.02, 0.5):
        r = check_depth(PressLimits(), H, 0.02, 0.02, bad)
        assert r.rule == "depth" and "between 0 and the block's thickness 0.02 m" in r.message


def test_the_plausible_modulus_is_the_stiffest_press_times_the_largest_lump_ratio():
    assert plausible_modulus([], [], 3.0) is None
    E = plausible_modulus([math.log(5e4), math.log(6e4)], [0.01, 0.02], 3.0)
    assert E == pytest.approx(3.0 * 6e4 * math.exp(UPPER_Z * 0.02), rel=1e-12)


def test_a_press_over_the_predicted_force_is_refused():
    E = 1.7e5
    assert hertz(E, 0.002) < 4.0 < hertz(E, 0.004)
    assert check_force(LIMITS, hertz, E, 0.02, 0.02, 0.002) is None
    assert check_force(LIMITS, hertz, E, 0.02, 0.02, None) is None
    r = check_force(LIMITS, hertz, E, 0.02, 0.02, 0.004)
    assert r.rule == "force"
    assert f"predicted peak force {hertz(E, 0.004):.3g} N exceeds --max-force 4 N" in r.message
    assert "E = 1.7e+05 Pa" in r.message and "shallower allowed depth" in r.message
    # nothing to predict with: no modulus yet, no law, no limit
    assert check_force(LIMITS, hertz, None, 0.02, 0.02, 0.004) is None
    assert check_force(LIMITS, None, E, 0.02, 0.02, 0.004) is None
    assert check_force(PressLimits(), hertz, E, 0.02, 0.02, 0.004) is None


def test_check_press_says_the_first_rule_broken():
    E = 1.7e5
    kw = {"E": E, "force_at": hertz}
    assert check_press(FOOTPRINT, KEEP, H, LIMITS, 0.02, 0.02, 0.002, **kw) is None
    assert check_press(FOOTPRINT, KEEP, H, LIMITS, 0.05, 0.02, 0.003, **kw).rule == "footprint"
    assert check_press(FOOTPRINT, KEEP, H, LIMITS, 0.03, 0.01, 0.003, **kw).rule == "keep-out"
    assert check_press(FOOTPRINT, KEEP, H, LIMITS, 0.02, 0.02, 0.003, **kw).rule == "depth"
    assert check_press(FOOTPRINT, KEEP, H, LIMITS, 0.02, 0.02, 0.004, **kw).rule == "force"


@pytest.mark.parametrize("text", ["0.1,x", "0.1,1.2", "0", "-0.1", "nan"])
def test_depths_are_fractions_of_the_thickness(text):
    with pytest.raises(InputError, match="--depths"):
        parse_depths(text)


def test_next_init_records_the_limits_and_old_states_have_none(tmp_path, capsys):
    d = tmp_path / "s"
    assert main(["next", str(d), "--init", "--footprint", "0,0.042,0,0.042", "--thickness",
                 "0.02", *TIP, "--depths", "0.2,0.1", "--max-force", "4"]) == 0
    assert "depths 0.2,0.1 of the thickness; max force 4 N" in capsys.readouterr().out
    rec = json.loads((d / "search.json").read_text())
    assert (rec["depths"], rec["max_force_n"], rec["depth_m"]) == ([0.2, 0.1], 4.0, 0.002)
    assert read_limits(d) == PressLimits(depths=(0.2, 0.1), max_force=4.0, depth=0.002)
    for key in ("depths", "max_force_n"):  # a state written before the limits existed
        del rec[key]
    (d / "search.json").write_text(json.dumps(rec))
    assert read_limits(d) == PressLimits(depth=0.002)
    assert main(["next", str(d), "--json"]) == 10
    assert main(["next", str(d), "--max-force", "4"]) == 2
    assert "--max-force belong(s) to --init" in capsys.readouterr().err
    assert main(["next", str(tmp_path / "t"), "--init", "--footprint", "0,0.042,0,0.042",
                 "--thickness", "0.02", *TIP, "--depths", "0.1,1.5"]) == 2
    assert "in (0, 1)" in capsys.readouterr().err


def test_a_send_gives_up_when_the_peer_stops_reading():
    with listen(0) as server:
        robot = socket.socket()
        robot.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        robot.connect(("127.0.0.1", server.getsockname()[1]))
        conn = accept_session(server, send_timeout=0.3)
        try:
            start, sent = time.monotonic(), 0
            while conn.send("x" * 1000) and time.monotonic() - start < PATIENCE:
                sent += 1  # fills the buffers (a few MB on loopback), then waits 0.3 s
            took = time.monotonic() - start
            assert conn.send_timed_out and sent > 10
            assert conn.broken == ("a line could not be sent within 0.3 s: the peer stopped "
                                   "reading")
            t0 = time.monotonic()
            assert conn.send("more") is False and time.monotonic() - t0 < 0.1
            assert took < PATIENCE
        finally:
            conn.close(0.0)
            robot.close()


# -- the loop on loopback: a real follow process ---------------------------------------------

def _connect(port: int, first: str, rows: list[str] | None = None, *,
             stop_on_stop_line: bool = True) -> list[dict]:
    """A robot's connection: its press line, then (if it is accepted) the samples a block at
    a time until the stop line; every line received."""
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE) as s:
        got = Received(s)
        s.sendall(first.encode())
        lines = [got.next()]
        if lines[0]["event"] == "refused":  # one line, then the connection ends
            s.shutdown(socket.SHUT_WR)
            assert s.recv(1) == b""
            return lines
        assert lines[0]["event"] == "accepted"
        s.sendall(b"time_s,z_m,force_n\n")
        for i in range(0, len(rows), 100):
            s.sendall("".join(rows[i:i + 100]).encode())
            while True:
                lines.append(got.next())
                if lines[-1]["event"] == "stop" or lines[-1].get("n", 0) >= i + 100:
                    break
            if lines[-1]["event"] == "stop" and stop_on_stop_line:
                break
        s.shutdown(socket.SHUT_WR)
        while "decision" not in lines[-1]:
            lines.append(got.next())
    return lines


def _stiff(rows: list[str], factor: float) -> list[str]:
    """The samples of a spot ``factor`` times stiffer (the force above its start scaled)."""
    arr = np.array([[float(v) for v in r.split(",")] for r in rows])
    f0 = np.median(arr[:50, 2])
    arr[:, 2] = f0 + factor * (arr[:, 2] - f0)
    return [f"{t!r},{z!r},{f!r}\n" for t, z, f in arr.tolist()]


@pytest.fixture(scope="module")
def unsafe(tmp_path_factory):
    """One follow process: an off-footprint, a keep-out, a bad-depth press (all refused), a
    normal press, one over the predicted force (refused), one whose measured force reaches
    the limit (stopped), and the normal press that spends the budget of two."""
    folder = tmp_path_factory.mktemp("safe") / "search"
    assert main(["next", str(folder), "--init", "--footprint", "0,0.042,0,0.042",
                 "--thickness", "0.02", *TIP, "--keep-out", "0.03,0.01,0.004",
                 "--depths", "0.1,0.2", "--max-force", "4"]) == 0
    follow = Follow(folder, "--max-depth", "0.0015", "--budget", "2")
    conns, rows = {}, {}
    try:
        x, y = 0.022, 0.022  # the first press of 'palpbayes next' on this footprint
        trace = _samples(PHANTOM.press(x, y, key=1))
        plan = [("off footprint", "press 0.05 0.01 0.002\n", None),
                ("keep-out", "press 0.031 0.012\n", None),
                ("depth", f"press {x!r} {y!r} 0.003\n", None),
                ("normal", f"press {x!r} {y!r} 0.002\n", trace),
                ("predicted force", None, None),
                ("measured force", None, None),
                ("after", None, None)]
        for key, first, samples in plan:
            if key == "predicted force":
                first = f"press {x!r} {y!r} 0.004\n"
            elif key in ("measured force", "after"):
                first = f"press {x!r} {y!r} 0.002\n"
                samples = _samples(PHANTOM.press(x, y, key=len(conns)))
                if key == "measured force":
                    samples = _stiff(samples, 12.0)
            conns[key] = _connect(follow.port, first, samples)
            rows[key] = len(pd.read_csv(folder / "presses.csv"))
            answer = conns[key][-1]
            if answer.get("event") == "next":
                x, y = answer["presses"][0]["x_m"], answer["presses"][0]["y_m"]
        rc = follow.wait()
    finally:
        follow.kill()
    return {"folder": folder, "conns": conns, "rows": rows, "rc": rc, "out": follow.out,
            "err": "".join(follow.err)}


@pytest.mark.parametrize("key, rule, words", [
    ("off footprint", "footprint", "press at (0.05, 0.01) m is off the footprint x 0 to "
                                   "0.042 m, y 0 to 0.042 m"),
    ("keep-out", "keep-out", "press at (0.031, 0.012) m is inside keep-out zone 1 (centre "
                             "(0.03, 0.01) m, radius 0.004 m"),
    ("depth", "depth", "depth 0.003 m: the depth is not an allowed depth (--depths)"),
    ("predicted force", "force", "depth 0.004 m: its predicted peak force"),
])
def test_an_unsafe_press_gets_one_refused_line_and_is_not_recorded(unsafe, key, rule, words):
    lines = unsafe["conns"][key]
    assert len(lines) == 1
    refused = lines[0]
    assert (refused["event"], refused["rule"]) == ("refused", rule)
    assert words in refused["message"] and "not pressed, not recorded" in refused["message"]
    assert f"refused: {refused['message']}" in unsafe["err"]
    before = {"off footprint": 0, "keep-out": 0, "depth": 0, "predicted force": 1}[key]
    assert unsafe["rows"][key] == before


def test_the_predicted_force_is_the_contact_law_at_the_plausible_modulus(unsafe):
    df = pd.read_csv(unsafe["folder"] / "presses.csv")
    E = 3.0 * math.exp(df["logE_mean"].iloc[0] + UPPER_Z * df["logE_sd"].iloc[0])
    msg = unsafe["conns"]["predicted force"][0]["message"]
    assert f"predicted peak force {hertz(E, 0.004):.3g} N exceeds --max-force 4 N" in msg
    assert f"E = {E:.4g} Pa" in msg
    accepted = unsafe["conns"]["after"][0]
    assert accepted["predicted_force_n"] == pytest.approx(hertz(E, 0.002), rel=1e-9)
    assert accepted["max_force_n"] == 4.0 and accepted["depth_m"] == 0.002
    assert unsafe["conns"]["normal"][0]["predicted_force_n"] is None  # no press yet


def test_a_measured_force_over_the_limit_stops_the_press_and_is_not_recorded(unsafe):
    lines = unsafe["conns"]["measured force"]
    assert lines[0]["event"] == "accepted"
    stop = next(r for r in lines if r["event"] == "stop")
    assert (stop["final"], stop["stop"]) == (False, "max force")
    assert stop["force_n"] >= 4.0 and stop["depth_m"] < 0.0015  # before the press's depth
    answer = lines[-1]
    assert "force limit --max-force 4 N was reached" in answer["warning"]
    assert "not added to the search" in answer["warning"] and answer["n"] == 1
    assert unsafe["rows"]["measured force"] == 1


def test_a_normal_press_after_the_unsafe_ones_is_accepted_and_recorded(unsafe):
    assert [unsafe["rows"][k] for k in ("normal", "after")] == [1, 2]
    for key in ("normal", "after"):
        lines = unsafe["conns"][key]
        assert lines[0]["event"] == "accepted" and "warning" not in lines[-1]
        assert next(r for r in lines if r["event"] == "stop")["stop"] == "max depth"
    df = pd.read_csv(unsafe["folder"] / "presses.csv")
    first = unsafe["conns"]["normal"][0]
    assert (df["x_m"].iloc[0], df["y_m"].iloc[0]) == (first["x_m"], first["y_m"])
    # two depths allowed: the search chooses each press's depth, and each is recorded; a
    # 4 mm press is predicted over the 4 N limit (refused above), so the search never names it
    assert df["depth_m"].tolist() == [0.002, 0.002]
    nxt = unsafe["conns"]["normal"][-1]["presses"][0]
    assert (nxt["criterion"], nxt["depth_m"]) == ("eig", 0.002)
    assert unsafe["rc"] == EXIT_UNDECIDED, unsafe["err"]
    assert "Traceback" not in unsafe["err"]
    # the refusals are on stdout too: the socket carries every line stdout does
    assert [json.loads(ln) for ln in unsafe["out"]] == [
        r for got in unsafe["conns"].values() for r in got]


# -- a robot that stops reading: the loop in this process, a press that says a lot -----------

def _state(E: float) -> OnlineState:
    s = MixtureSummary(mean=E, sd=E / 100, median=E, lo=0.98 * E, hi=1.02 * E, level=0.9)
    return OnlineState(n=10, t=1.0, z=0.1, in_contact=True, n_contact=5, depth=1e-3,
                       peak_force=0.1, E=s, z_surf=None, stop="", E_total=s)


def _loop_in_process(tmp_path, monkeypatch, press, **timeouts):
    """follow --map's loop in a thread of this process on a new search state (budget 1),
    its presses made by ``press``: (folder, port, the lines it said, its exit status list,
    the thread)."""
    folder = tmp_path / "s"
    assert main(["next", str(folder), "--init", "--footprint", "0,0.042,0,0.042",
                 "--thickness", "0.02", *TIP, "--depth", "0.002"]) == 0
    server = listen(0)
    monkeypatch.setattr(follow_map, "_listen", lambda address: server)
    said: list[str] = []
    args = Namespace(map=str(folder), listen="0", criterion="eig", p_decide=0.95,
                     centre_radius=2e-3, budget=1, json=True, tip="paraboloid",
                     radius=0.0117, max_depth=None, depths=None, max_force=None, **timeouts)
    result: list[int] = []
    loop = threading.Thread(target=lambda: result.append(
        follow_map.live_loop(args, press, said.append)), daemon=True)
    loop.start()
    return folder, server.getsockname()[1], said, result, loop


def test_a_robot_that_stops_reading_loses_its_press_and_the_loop_goes_on(tmp_path, capsys,
                                                                          monkeypatch):
    calls: list[int] = []

    def press(lines, source, emit, depth):
        calls.append(len(calls))
        if len(calls) == 1:  # far more than the socket's buffers hold
            for _ in range(6000):
                emit(json.dumps({"event": "update", "pad": "x" * 1000}))
        else:
            for _ in lines:
                pass
            emit(json.dumps({"event": "update"}))
        return _state(5e4)

    folder, port, said, result, loop = _loop_in_process(tmp_path, monkeypatch, press,
                                                        send_timeout=0.3)
    deaf = socket.socket()
    deaf.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    deaf.connect(("127.0.0.1", port))
    deaf.sendall(b"press 0.022 0.022\n")  # and never reads
    start = time.monotonic()
    while len(said) < 6001 and time.monotonic() - start < PATIENCE:  # accepted + 6000
        time.sleep(0.05)
    time.sleep(0.2)
    deaf.close()
    lines = _connect(port, "press 0.02 0.03\n", [])
    loop.join(PATIENCE)
    err = capsys.readouterr().err
    assert result == [EXIT_UNDECIDED], err
    assert "error: tcp 127.0.0.1:" in err
    assert ("a line could not be sent within 0.3 s: the peer stopped reading; the press at "
            "(0.022, 0.022) m is not added") in err
    assert "connection closed, waiting for the next press" in err
    # the dropped press has no answer; the next one is accepted and recorded
    assert not any("decision" in json.loads(s) for s in said[:6001])
    assert lines[0] == {"event": "accepted", "x_m": 0.02, "y_m": 0.03, "depth_m": 0.002,
                        "max_force_n": None, "predicted_force_n": None}
    assert lines[-1]["event"] == "done" and lines[-1]["n"] == 1
    df = pd.read_csv(folder / "presses.csv")
    assert len(df) == 1 and (df["x_m"].iloc[0], df["y_m"].iloc[0]) == (0.02, 0.03)


def test_a_robot_that_stalls_mid_press_loses_it_and_the_loop_goes_on(tmp_path, capsys,
                                                                       monkeypatch):
    def press(lines, source, emit, depth):
        n = sum(1 for _ in lines)  # ends when the robot closes, or stalls past the timeout
        emit(json.dumps({"event": "update", "lines": n}))
        return _state(5e4)

    folder, port, said, result, loop = _loop_in_process(tmp_path, monkeypatch, press,
                                                        send_timeout=5.0, sample_timeout=0.5)
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE) as stalled:
        got = Received(stalled)
        stalled.sendall(b"press 0.022 0.022\ntime_s,z_m,force_n\n0.0,0.1,0.0\n")
        t0 = time.monotonic()
        seen = [got.next()]
        while seen[-1]["event"] != "error":
            seen.append(got.next())
        waited = time.monotonic() - t0
        # and the robot never closes: the loop closes it and takes the next connection
        lines = _connect(port, "press 0.02 0.03\n", [])
    loop.join(PATIENCE)
    err = capsys.readouterr().err
    assert result == [EXIT_UNDECIDED], err
    assert seen[0]["event"] == "accepted" and 0.5 <= waited < PATIENCE
    assert ("no sample for 0.5 s (--sample-timeout); the press at (0.022, 0.022) m is not "
            "added; connection closed, waiting for the next press") in seen[-1]["message"]
    assert f"error: {seen[-1]['message']}" in err
    assert not any("decision" in r for r in seen)  # the dropped press has no answer
    assert lines[0]["event"] == "accepted" and lines[-1]["event"] == "done"
    df = pd.read_csv(folder / "presses.csv")
    assert len(df) == 1 and (df["x_m"].iloc[0], df["y_m"].iloc[0]) == (0.02, 0.03)
