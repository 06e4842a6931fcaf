"""``palpbayes follow``: live samples stop at the same sample as ``replay`` on the same data."""

from __future__ import annotations

import io
import json
import socket
import sys
import threading
import time

import pytest

from palpbayes.cli import follow as follow_cli
from palpbayes.cli import main
from palpbayes.errors import StreamError
from palpbayes.fitdata import ModelSpec
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.online import OnlineEstimator, StoppingRule, replay
from palpbayes.online.stream import SampleParser, batches
from palpbayes.online.tcp import DEFAULT_HOST, accept_lines, listen
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

E_TRUE = 1.25e5
TIP = ["--tip", "paraboloid", "--radius", "0.0117"]
RULES = {  # CLI options, the StoppingRule, the exit status
    "target precision": (["--target", "2%", "--target-on", "stat"], StoppingRule(target=0.02),
                         0),
    "max force": (["--max-force", "0.1"], StoppingRule(max_force=0.1), 3),
    "max depth": (["--max-depth", "3e-4"], StoppingRule(max_depth=3e-4), 4),
    "": (["--max-force", "50"], StoppingRule(max_force=50.0), 5),
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A simulated palpation at the sensor's 800 Hz, as the canonical CSV, its text and its
    JSON lines (the same numbers: each CSV field's float, written by json)."""
    tr = simulate_trace(E_TRUE, PAPER_TIPS["paraboloid"], thickness=0.03, force_offset=0.05,
                        rng=17, base=None, rate=800.0)
    path = write_trace(tr, tmp_path_factory.mktemp("follow") / "press.csv")
    text = path.read_text()
    rows = [ln.split(",") for ln in text.splitlines()[1:]]
    jsonl = "".join(json.dumps({"time_s": float(t), "z_m": float(z), "force_n": float(f)})
                    + "\n" for t, z, f in rows)
    return path, text, jsonl


def run_follow(monkeypatch, capsys, text: str, *args: str):
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    rc = main(["follow", *TIP, "--json", "--nu", "0.3", *args])
    out = capsys.readouterr()
    rows = [json.loads(ln) for ln in out.out.splitlines()]  # every line is JSON
    assert rows[-1]["event"] in ("stop", "end")
    return rc, [r for r in rows if r["event"] == "update"], out


@pytest.mark.parametrize("reason", list(RULES))
def test_follow_stops_at_the_sample_replay_stops_at(recorded, monkeypatch, capsys, reason):
    path, text, _ = recorded
    args, rule, status = RULES[reason]
    trace = read_trace(path, tip=PAPER_TIPS["paraboloid"])
    assert trace.time[1] - trace.time[0] == pytest.approx(1 / 800)
    res = replay(trace, rule=rule, chunk=100)
    rc, updates, out = run_follow(monkeypatch, capsys, text, *args, "--timeout", "0")
    assert rc == status, out.err
    last = updates[-1]
    assert last["stop"] == reason
    if reason:
        s = res.at_stop
        assert s.stop == reason
        assert (last["n"], last["t_s"], last["E_pa"], last["E_lo_pa"], last["E_hi_pa"]) == (
            s.n, s.t, s.E.median, s.E.lo, s.E.hi)
        final = json.loads(out.out.splitlines()[-1])
        assert (final["event"], final["stop"], final["n"]) == ("stop", reason, s.n)
        # every update replay made up to the stop, in order, and none after it
        assert [u["n"] for u in updates if u["in_contact"]] == res.history["n"].tolist()[
            : res.history["n"].tolist().index(s.n) + 1]
    else:
        assert res.at_stop is None
        assert last["n"] == res.final.n == trace.n_points and last["E_pa"] == res.final.E.median
        final = json.loads(out.out.splitlines()[-1])
        assert (final["event"], final["n"]) == ("end", 3840)


def test_csv_and_json_lines_give_identical_updates(recorded, monkeypatch, capsys):
    _, text, jsonl = recorded
    stat = ("--target", "2%", "--target-on", "stat")
    rc_csv, from_csv, _ = run_follow(monkeypatch, capsys, text, *stat)
    rc_json, from_json, _ = run_follow(monkeypatch, capsys, jsonl, *stat)
    assert rc_csv == rc_json == 0
    # the same updates, the line numbers one apart (the CSV header is line 1)
    assert [u["line"] for u in from_csv] == [u["line"] + 1 for u in from_json]
    drop = [{k: v for k, v in u.items() if k != "line"} for u in from_csv]
    assert drop == [{k: v for k, v in u.items() if k != "line"} for u in from_json]
    assert len(from_csv) == 14 and from_csv[-1]["n"] == 1400


def test_the_text_output_is_one_flushed_line_per_update(recorded, monkeypatch, capsys):
    _, text, _ = recorded
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--max-depth", "3e-4"]) == 4
    out = capsys.readouterr()
    lines = out.out.splitlines()
    assert lines[0].startswith("n    100  t    0.125 s  no contact yet")
    assert "E = " in lines[-2] and "(±" in lines[-2] and lines[-1].startswith("stop: max depth")
    assert "nu = 0.3 assumed" in out.err


def test_tcp_connect_on_loopback_with_an_ephemeral_port(recorded, monkeypatch, capsys):
    """palpbayes connects to the robot's server: the same stop as from stdin."""
    _, text, _ = recorded
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve():
        conn, _ = server.accept()
        with conn:
            conn.sendall(text.encode())
            conn.shutdown(socket.SHUT_WR)
            conn.recv(1)  # until follow closes its end
        server.close()

    threading.Thread(target=serve, daemon=True).start()
    rc = main(["follow", *TIP, "--json", "--nu", "0.3", "--max-force", "0.1", "--connect",
               f"127.0.0.1:{port}"])
    updates = [r for r in map(json.loads, capsys.readouterr().out.splitlines())
               if r["event"] == "update"]
    rc_stdin, from_stdin, _ = run_follow(monkeypatch, capsys, text, "--max-force", "0.1")
    assert rc == rc_stdin == 3 and updates == from_stdin


def test_the_listener_binds_loopback_by_default(recorded, monkeypatch, capsys):
    """--listen PORT binds 127.0.0.1; the robot connects and streams in its own time."""
    _, text, _ = recorded
    bound = {}
    ready = threading.Event()

    def spy(port, host=DEFAULT_HOST):
        s = listen(port, host)
        bound["address"] = s.getsockname()
        ready.set()
        return s

    monkeypatch.setattr(follow_cli, "listen", spy)

    def robot():
        assert ready.wait(10)
        with socket.create_connection(bound["address"][:2]) as c:
            for i in range(0, len(text), 4096):  # in pieces, as a socket delivers them
                c.sendall(text[i:i + 4096].encode())

    threading.Thread(target=robot, daemon=True).start()
    rc = main(["follow", *TIP, "--json", "--max-depth", "3e-4", "--listen", "0"])
    out = capsys.readouterr()
    assert bound["address"][0] == "127.0.0.1" == DEFAULT_HOST
    assert f"listening on 127.0.0.1:{bound['address'][1]}" in out.err
    assert rc == 4 and json.loads(out.out.splitlines()[-2])["stop"] == "max depth"


def test_the_library_listener_streams_to_the_estimator(recorded):
    path, text, _ = recorded
    server = listen(0)
    assert server.getsockname()[0] == "127.0.0.1"

    def robot():
        with socket.create_connection(server.getsockname()) as c:
            c.sendall(text.encode())

    threading.Thread(target=robot, daemon=True).start()
    lines, peer = accept_lines(server)
    server.close()
    assert peer.startswith("127.0.0.1:")
    rule = StoppingRule(max_force=0.1)
    est = OnlineEstimator(ModelSpec(PAPER_TIPS["paraboloid"], nu=0.3), rule=rule)
    with lines:
        state, latencies = follow_cli.follow(
            batches(lines, SampleParser(), chunk=100, limit=est.limit), est, lambda s: None)
    trace = read_trace(path, tip=PAPER_TIPS["paraboloid"])
    s = replay(trace, rule=rule).at_stop
    assert (state.stop, state.n, state.E.median) == ("max force", s.n, s.E.median)
    # the stop is the first sample whose force above the baseline reaches 0.1 N, in the
    # middle of a chunk: the chunks before it and the one the limit ended
    above = trace.force - est.baseline_level >= 0.1
    assert s.n == int(above.argmax()) + 1 and s.n % 100 != 0
    assert len(latencies) == s.n // 100 + 1 and all(0 <= x < 5 for x in latencies)


BAD = [  # (stream, line number, words the message must have)
    ("time_s,z_m,force_n\n0.1,0.1,0.0\n0.2,0.1\n", 3, ["2 fields", "header names 3"]),
    ("time_s,z,force_n\n0.1,0.1,0.0\n", 1, ["missing column 'z_m'", "--z-column"]),
    ("timestamp,tcp_z_mm,fz\n0.1,100,0.0\n", 1,
     ["'z_m' (a robot log's 'tcp_z_mm'? map it with --z-column tcp_z_mm --z-unit mm",
      "'time_s' (a robot log's 'timestamp'? map it with --time-column timestamp"]),
    ("Time_S,z_m,force_n\n0.1,0.1,0.0\n", 1,
     ["'time_s' (the header's 'Time_S' differs from it in case only: --time-column Time_S)"]),
    ("0.1,0.1,0.0\n", 1, ["missing column", "starts with its header"]),
    ("time_s,z_m,force_n\n0.1,0.1,0.0\n0.2,nan,0.0\n", 3, ["z_m = 'nan' is not finite"]),
    ("time_s,z_m,force_n\n0.1,0.1,0.0\n0.2,0.1,abc\n", 3, ["force_n = 'abc' is not a number"]),
    ("time_s;z_m;force_n\n0.1;0,1;0.0\n", 2, ["z_m = '0,1'", "decimal comma"]),
    ("time_s,z_m,force_n\n0.2,0.1,0.0\n0.1,0.1,0.0\n", 3, ["time goes backwards",
                                                          "time order"]),
    ('{"time_s": 0.1, "z_m": 0.1, "force_n": 0}\n{"time_s": 0.2, "z_m": 0.1\n', 2,
     ["not a JSON object", "one JSON object per line"]),
    ('{"time_s": 0.1, "z_m": 0.1, "force_n": 0}\n{"time_s": 0.2, "z_m": 0.1}\n', 2,
     ["missing key 'force_n'"]),
    ('{"time_s": 0.1, "z_m": 0.1, "force_n": 0}\n{"time_s": 0.2, "z_m": 0.1, '
     '"force_n": NaN}\n', 2, ["force_n = nan is not finite"]),
    ('{"time_s": 0.1, "z_m": 0.1, "force_n": 0}\n{"time_s": 0.2, "z_m": true, '
     '"force_n": 0}\n', 2, ["z_m = True is not a number"]),
    ('[0.1, 0.1, 0.0]\n', 1, ["missing column"]),
]


@pytest.mark.parametrize("stream, line, words", BAD)
def test_a_bad_line_is_named_and_exits_with_status_2(monkeypatch, capsys, stream, line, words):
    monkeypatch.setattr(sys, "stdin", io.StringIO(stream))
    rc = main(["follow", *TIP, "--target", "2%"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert rc == follow_cli.EXIT_BAD_INPUT == 2
    assert err.startswith(f"palpbayes follow: error: stdin line {line}: "), err
    for w in words:
        assert w in err, err
    assert "Traceback" not in err
    with pytest.raises(StreamError) as info:
        list(batches(io.StringIO(stream), SampleParser(), chunk=1))
    assert info.value.line == line


def test_units_signs_and_column_names_are_the_trace_readers():
    p = SampleParser(columns={"force": "Fz"}, units={"z": "mm", "force": "mN"},
                     force_sign=-1, z_sign=-1)
    assert p.parse("t_ignored\ttime_s\tz_m\tFz", 1) is None
    assert p.parse("9\t0.5\t2\t-30", 2) == (0.5, -0.002, 0.03)


def test_a_partial_chunk_at_the_end_and_after_the_timeout():
    lines = ["time_s,z_m,force_n\n"] + [f"{k / 800},0.1,0.0\n" for k in range(1, 251)]
    got = list(batches(iter(lines), SampleParser(), chunk=100, timeout=None))
    assert [(b.size, b.why, b.last_line) for b in got] == [(100, "chunk", 101),
                                                            (100, "chunk", 201),
                                                            (50, "end", 251)]

    def slow():
        yield from lines[:4]
        time.sleep(0.4)  # the robot pauses: three samples wait for a decision
        yield from lines[4:6]

    got = list(batches(slow(), SampleParser(), chunk=100, timeout=0.1))
    assert [(b.size, b.why) for b in got] == [(3, "timeout"), (2, "end")]


def test_follow_takes_replays_options_and_refuses_a_missing_rule(monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    assert main(["follow", *TIP]) == 2
    assert "give a stopping rule" in capsys.readouterr().err
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    assert main(["follow", *TIP, "--max-force", "1"]) == 5
    assert "ended after 0 samples" in capsys.readouterr().out


def test_help_documents_the_exit_statuses(capsys):
    with pytest.raises(SystemExit):
        main(["follow", "--help"])
    text = capsys.readouterr().out
    for code, what in ((0, "target precision"), (3, "max force"), (4, "max depth"),
                       (5, "stream ended"), (2, "bad input")):
        assert f"  {code}    " in text and what in text
    assert "127.0.0.1" in text
