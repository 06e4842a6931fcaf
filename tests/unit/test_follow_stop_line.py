"""``palpbayes follow``'s stop line (issue 47): said the moment the stop is known, before the
posterior work behind it.  Behaviour only: the latencies are measured by
``benchmarks/bench_follow.py``."""

from __future__ import annotations

import io
import json
import sys
import threading

import pytest

from palpbayes.cli import follow as follow_cli
from palpbayes.cli import main
from palpbayes.cli.follow_lines import StopLine
from palpbayes.fitdata import ModelSpec
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.online import OnlineEstimator, StoppingRule, replay
from palpbayes.online.stream import SampleParser, batches
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

TIP = ["--tip", "paraboloid", "--radius", "0.0117"]
#: A wait that only a bug makes long [s].
PATIENCE = 20.0


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """The palpation of test_follow: 800 Hz, as CSV text, and the trace read back."""
    tr = simulate_trace(1.25e5, PAPER_TIPS["paraboloid"], thickness=0.03, force_offset=0.05,
                        rng=17, base=None, rate=800.0)
    path = write_trace(tr, tmp_path_factory.mktemp("stop") / "press.csv")
    return path.read_text(), read_trace(path, tip=PAPER_TIPS["paraboloid"])


def _events(monkeypatch):
    """Record, in order, the lines follow prints and the estimator's work: ("line", text),
    ("update", n after it) as an update begins, ("total", n) as its full interval begins."""
    events: list[tuple[str, object]] = []
    lock = threading.Lock()

    def say(line: str) -> None:
        with lock:
            events.append(("line", line))

    update, total = OnlineEstimator.update, OnlineEstimator._total

    def spy_update(self, t, z, force, on_stop=None):
        with lock:
            events.append(("update", self.n_kept + len(t)))
        return update(self, t, z, force, on_stop=on_stop)

    def spy_total(self, *args, **kwargs):
        with lock:
            events.append(("total", self.n_kept))
        return total(self, *args, **kwargs)

    monkeypatch.setattr(follow_cli, "_say", say)
    monkeypatch.setattr(OnlineEstimator, "update", spy_update)
    monkeypatch.setattr(OnlineEstimator, "_total", spy_total)
    return events


def _stop_lines(events) -> list[tuple[int, dict]]:
    rows = [(k, json.loads(e)) for k, (what, e) in enumerate(events) if what == "line"]
    return [(k, r) for k, r in rows if r["event"] == "stop" and not r["final"]]


@pytest.mark.parametrize("args, rule, reason, status", [
    (["--max-force", "0.1"], StoppingRule(max_force=0.1), "max force", 3),
    (["--max-depth", "3e-4"], StoppingRule(max_depth=3e-4), "max depth", 4),
])
def test_a_limit_is_said_at_its_sample_before_any_posterior_work_on_it(
        recorded, monkeypatch, args, rule, reason, status):
    """The stop line of a max force or depth comes from the very sample that reached it, in
    the middle of its chunk, before the update on the samples up to it begins."""
    text, trace = recorded
    s = replay(trace, rule=rule, chunk=100).at_stop
    assert s.stop == reason and s.n % 100 != 0
    events = _events(monkeypatch)
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--json", "--nu", "0.3", "--timeout", "0", *args]) == status
    (at, stop), = _stop_lines(events)  # one stop line
    assert (stop["stop"], stop["n"], stop["line"]) == (reason, s.n, s.n + 1)  # + the header
    assert stop["t_s"] == s.t and stop["z_m"] == s.z
    assert stop["E_pa"] is None  # judged before any posterior work
    limit = {"max force": ("force_n", 0.1), "max depth": ("depth_m", 3e-4)}[reason]
    assert stop[limit[0]] >= limit[1]
    assert events.index(("update", s.n)) > at  # the update on the samples up to it: after
    updates = [json.loads(e) for what, e in events if what == "line"
               and json.loads(e)["event"] == "update"]
    assert [u["stop"] for u in updates if u["stop"]] == [reason]
    assert updates[-1]["n"] == s.n and updates[-1]["stop"] == reason
    final = json.loads(events[-1][1])
    assert (final["event"], final["final"], final["stop"], final["n"]) == ("stop", True,
                                                                           reason, s.n)


def test_a_target_is_said_before_the_full_interval_of_its_update(recorded, monkeypatch):
    """A statistical target needs no budget draws: the stop line comes after the update's
    posterior and before its full interval (the draws), then the update, then the checks."""
    text, _ = recorded
    events = _events(monkeypatch)
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--json", "--nu", "0.3", "--timeout", "0", "--target", "2%",
                 "--target-on", "stat"]) == 0
    (at, stop), = _stop_lines(events)
    assert (stop["stop"], stop["n"]) == ("target precision", 1400)
    assert stop["rel_half_width"] <= 0.02 and stop["E_lo_pa"] < stop["E_pa"] < stop["E_hi_pa"]
    assert events.index(("update", 1400)) < at < events.index(("total", 1400))
    update = json.loads(events[-2][1])
    assert (update["event"], update["n"], update["stop"]) == ("update", 1400,
                                                              "target precision")
    assert update["E_pa"] == stop["E_pa"] and update["E_total_lo_pa"] is not None


def test_a_full_target_is_said_once_its_full_interval_is_known(recorded, monkeypatch):
    text, _ = recorded
    events = _events(monkeypatch)
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--json", "--nu", "0.3", "--timeout", "0", "--target",
                 "5%"]) == 0
    (at, stop), = _stop_lines(events)
    assert stop["stop"] == "target precision"
    assert events.index(("total", stop["n"])) < at  # it needs the draws
    assert json.loads(events[-2][1])["n"] == stop["n"]


def test_no_stop_line_when_the_stream_ends_first(recorded, monkeypatch):
    text, _ = recorded
    events = _events(monkeypatch)
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--json", "--nu", "0.3", "--max-force", "50"]) == 5
    assert _stop_lines(events) == []
    assert json.loads(events[-1][1])["event"] == "end"


def test_the_text_stop_line_gives_the_sample_the_force_and_the_depth(recorded, monkeypatch,
                                                                     capsys):
    text, trace = recorded
    s = replay(trace, rule=StoppingRule(max_force=0.1), chunk=100).at_stop
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["follow", *TIP, "--nu", "0.3", "--max-force", "0.1"]) == 3
    lines = capsys.readouterr().out.splitlines()
    said = [ln for ln in lines if ln.startswith("stop:")]
    assert len(said) == 2 and said[1] == lines[-1]  # the stop line, and the last line
    assert said[0].startswith(f"stop: max force at n {s.n} (t {s.t:.4f} s): force ")
    assert "above the baseline, depth " in said[0]
    assert said[0].endswith("; the update and the model checks follow")
    assert lines[-1].startswith(f"stop: max force at n {s.n} (t {s.t:.4f} s); model checks")
    assert lines.index(said[0]) < len(lines) - 2 and "E = " in lines[-2]


def _gated(text: str, upto: int, gate: threading.Event):
    """The lines of ``text``: the header and ``upto`` samples, then the rest once ``gate``
    is set (a robot whose next samples arrive while an update is running)."""
    rows = text.splitlines(keepends=True)
    yield from rows[:upto + 1]
    assert gate.wait(PATIENCE)
    yield from rows[upto + 1:]


@pytest.mark.parametrize("rule, hold", [
    # a max force alone needs only the baseline (read at contact): judged at once, even
    # before the update before it has set anything
    (StoppingRule(max_force=0.3), "update"),
    # a max depth needs the surface: judged at once as soon as the running update has set
    # it, while its full interval (the draws, most of an update) is still being computed
    (StoppingRule(max_depth=3e-4), "_total"),
])
def test_a_limit_reached_while_an_update_runs_is_said_during_it(recorded, rule, hold):
    """The update on the chunk before the crossing is held (in ``hold``) until the stop line
    is said: the stop must not wait for it, and is the sample replay stops at."""
    text, trace = recorded
    s = replay(trace, rule=rule, chunk=100).at_stop
    before = (s.n - 1) // 100 * 100  # the last sample of the chunk before
    est = OnlineEstimator(ModelSpec(PAPER_TIPS["paraboloid"], nu=0.3), rule=rule, total=True,
                          budget_draws=1000)
    started, said = threading.Event(), threading.Event()
    held: list[bool] = []
    original = getattr(est, hold)

    def held_work(*args, **kwargs):
        # the update on the chunk before the crossing, before it begins or in its draws
        if (est.n_kept + len(args[0]) if hold == "update" else est.n_kept) == before:
            started.set()  # the robot's next samples arrive now
            held.append(said.wait(PATIENCE))
        return original(*args, **kwargs)

    setattr(est, hold, held_work)
    lines: list[str] = []

    def emit(line: str) -> None:
        lines.append(line)
        if line.startswith("{") and json.loads(line)["event"] == "stop":
            said.set()

    stop_line = StopLine(emit, est, as_json=True)
    stream = batches(_gated(text, before, started), SampleParser(), chunk=100,
                     limit=est.limit, on_limit=stop_line.limit, current=est.limit_current)
    state, _ = follow_cli.follow(stream, est, emit, as_json=True, stop_line=stop_line)
    assert held == [True]  # said while the update was held
    rows = [json.loads(ln) for ln in lines]
    (at,) = [k for k, r in enumerate(rows) if r["event"] == "stop"]
    assert (rows[at]["stop"], rows[at]["n"]) == (s.stop, s.n)
    # said before the line of the update it did not wait for
    assert [r["n"] for r in rows[at + 1:]] == [before, s.n]
    assert (state.stop, state.n, state.E.median) == (s.stop, s.n, s.E.median)


def test_the_stream_names_the_sample_a_limit_ends_its_batch_at(recorded):
    text, trace = recorded
    rule = StoppingRule(max_force=0.1)
    s = replay(trace, rule=rule, chunk=100).at_stop
    est = OnlineEstimator(ModelSpec(PAPER_TIPS["paraboloid"], nu=0.3), rule=rule)
    hits = []
    got = []
    for b in batches(io.StringIO(text), SampleParser(), chunk=100, timeout=None,
                     limit=est.limit, on_limit=hits.append):
        got.append((b.size, b.why))
        est.update(b.t, b.z, b.force)
    assert got[-1] == (s.n % 100, "limit") and sum(n for n, _ in got) == s.n
    (hit,) = hits
    assert (hit.reason, hit.n, hit.line, hit.t, hit.z) == ("max force", s.n, s.n + 1, s.t, s.z)
    assert hit.force - est.baseline_level >= 0.1


def test_the_estimator_says_its_stop_once_and_a_limit_decides_the_update(recorded):
    _, trace = recorded
    seg = trace.loading_segment()
    est = OnlineEstimator(ModelSpec(PAPER_TIPS["paraboloid"], nu=0.3),
                          rule=StoppingRule(max_force=0.1, max_depth=1.0), total=True)
    said = []
    k = 0
    while True:  # chunks of 100, as replay
        state = est.update(seg.time[k:k + 100], seg.z[k:k + 100], seg.force[k:k + 100],
                           on_stop=said.append)
        k += 100
        if state.in_contact and state.E is not None:
            break
    assert said == [] and not state.should_stop
    # both limits reached at one sample: the force first, as StoppingRule.reason
    z, f = seg.z[k:k + 1] - 1.0, seg.force[k:k + 1] + 10.0
    assert est.limit(z, f) == (0, "max force")
    assert est.limit_current(est._updates) and not est.limit_current(est._updates + 1)
    state = est.update(seg.time[k:k + 1], z, f, on_stop=said.append)
    assert state.stop == "max force" and len(said) == 1 and said[0].stop == "max force"
    assert said[0].E_total is None and said[0].n == state.n  # before the full interval
    assert state.E_total is not None and state.force == pytest.approx(
        f[0] - est.baseline_level)
    assert est.limit(z, f) is None  # once the rule has fired
