"""What the online estimator and ``follow``'s reader keep of a long stream (issue 58, item 9):
bounded, whatever the stream's length, and a press within the bounds is estimated, stopped and
checked as by an estimator that keeps everything.  Sizes of what is stored are asserted, never
times or process memory."""

from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import pytest

import palpbayes.online.adequacy as adequacy
import palpbayes.online.samples as samples
from palpbayes.fitdata import ModelSpec
from palpbayes.online import OnlineEstimator, StoppingRule
from palpbayes.online.stream import SampleParser, batches
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

TIP = PAPER_TIPS["paraboloid"]
RATE = 800.0  # [Hz]


@pytest.fixture(scope="module")
def press():
    """The paper-like press of tests/unit/test_follow.py: 3,840 samples at 800 Hz, ~960 of
    them before the contact."""
    return simulate_trace(1.25e5, TIP, thickness=0.03, force_offset=0.05, rng=17, base=None,
                          rate=RATE)


def _waiting(tr, n: int, seed: int = 3):
    """``n`` samples of a robot waiting above the surface (z at the press's start with 1 µm
    of jitter, the force's offset and noise) before the press ``tr``: time, z, force."""
    rng = np.random.default_rng(seed)
    t = np.r_[np.arange(n) / RATE, tr.time + n / RATE]
    z = np.r_[tr.z[0] + 1e-6 * rng.standard_normal(n), tr.z]
    f = np.r_[0.05 + 0.008 * rng.standard_normal(n), tr.force]
    return t, z, f


def _run(est, t, z, f, chunk: int):
    """Feed ``est`` in chunks; every state."""
    return [est.update(t[i:i + chunk], z[i:i + chunk], f[i:i + chunk])
            for i in range(0, t.size, chunk)]


def _stored(est) -> int:
    """The length of the estimator's sample arrays (what it holds, with their spare room)."""
    return max(a.size for a in (est._kept.t, est._kept.z, est._kept.f))


def _same(a, b) -> bool:
    """Two states equal in every field (NaN equal to NaN)."""
    def eq(x, y):
        if isinstance(x, float) and isinstance(y, float):
            return x == y or (np.isnan(x) and np.isnan(y))
        if dataclasses.is_dataclass(x):
            return eq(dataclasses.astuple(x), dataclasses.astuple(y))
        if isinstance(x, tuple):
            return len(x) == len(y) and all(eq(u, v) for u, v in zip(x, y, strict=True))
        return x == y
    return eq(a, b)


def test_a_long_wait_before_the_press_keeps_a_bounded_window(press):
    """200,000 samples of waiting (4 min at 800 Hz) and the press: the estimator held every
    one of them (arrays of 262,144); now the last PRE_CONTACT_SAMPLES and the chunk, and
    after the contact the press.  The estimate is that of the recording that starts with the
    samples kept: the same summaries, n counting every sample."""
    chunk = 1000
    t, z, f = _waiting(press, 200_000)
    est = OnlineEstimator(ModelSpec(TIP), total=True)
    biggest = 0
    for i in range(0, t.size, chunk):
        s = est.update(t[i:i + chunk], z[i:i + chunk], f[i:i + chunk])
        biggest = max(biggest, _stored(est), est.n_kept)
        if not s.in_contact:
            assert est.n_kept <= samples.PRE_CONTACT_SAMPLES + chunk
    assert biggest <= 2 * (samples.PRE_CONTACT_SAMPLES + chunk) < 200_000
    assert est.n_kept < samples.PRE_CONTACT_SAMPLES + chunk + press.n_points
    assert s.n == t.size and s.E.rel_half_width < 0.01
    assert s.E.lo < 1.25e5 < s.E.hi
    # the recording that starts with what was kept, fed at the same chunk ends
    start = t.size - est.n_kept
    ref = OnlineEstimator(ModelSpec(TIP), total=True)
    first = chunk * -(-start // chunk) - start  # the kept samples up to the next chunk end
    ref.update(t[start:start + first], z[start:start + first], f[start:start + first])
    r = _run(ref, t[start + first:], z[start + first:], f[start + first:], chunk)[-1]
    assert _same(dataclasses.replace(s, n=r.n, t=r.t), r)


def test_a_press_within_the_bounds_is_what_it_was(press, monkeypatch):
    """Every state and the model checks of a normal press (3,840 samples; AR(1) noise too)
    with the bounds as shipped equal those of an estimator that keeps everything (the bounds
    raised out of reach), field by field."""
    ar1 = simulate_trace(1.25e5, TIP, thickness=0.03, noise_ar1=0.6, rng=3, base=None,
                         rate=RATE)

    def run(tr, noise):
        est = OnlineEstimator(ModelSpec(TIP), noise=noise, total=True,
                              rule=StoppingRule(target=0.01, target_on="stat"))
        states = _run(est, tr.time, tr.z, tr.force, 100)
        return states, est.model_checks()

    shipped = {k: run(tr, noise) for k, (tr, noise) in
               {"gaussian": (press, "gaussian"), "ar1": (ar1, "ar1")}.items()}
    for name in ("PRE_CONTACT_SAMPLES", "MAX_CONTACT_SAMPLES"):
        monkeypatch.setattr(samples, name, 10**9)
    monkeypatch.setattr(adequacy, "CHECK_SAMPLES", 10**9)
    for k, (tr, noise) in {"gaussian": (press, "gaussian"), "ar1": (ar1, "ar1")}.items():
        states, checks = run(tr, noise)
        assert len(states) == len(shipped[k][0]) and checks
        assert all(_same(a, b) for a, b in zip(states, shipped[k][0], strict=True))
        assert [(c.name, c.statistic, c.passed) for c in checks] == [
            (c.name, c.statistic, c.passed) for c in shipped[k][1]]
    assert any(s.should_stop for s in shipped["gaussian"][0])


def test_the_model_checks_see_at_most_check_samples(press, monkeypatch):
    """The checks ran on every sample kept: 400,000 samples held 3.2 GB in their
    posterior-predictive check.  Beyond CHECK_SAMPLES they run on an even thinning that keeps
    the last sample, with the noise's lag-one correlation at the stride; a good press still
    passes them."""
    seen = {}
    real = adequacy.run_checks

    def spy(z, force, model, **kw):
        seen.update(n=len(z), last=float(z[-1]), lag1=kw["baseline_lag1"])
        return real(z, force, model, **kw)

    monkeypatch.setattr(adequacy, "run_checks", spy)
    est = OnlineEstimator(ModelSpec(TIP))
    _run(est, press.time, press.z, press.force, 100)
    full = est.model_checks()
    assert seen["n"] == press.n_points
    lag1 = seen["lag1"]
    monkeypatch.setattr(adequacy, "CHECK_SAMPLES", 1000)
    thinned = est.model_checks()
    assert seen["n"] == 960 and seen["last"] == press.z[-1]  # stride 4: 3840 / 4
    assert seen["lag1"] == pytest.approx(lag1**4)
    assert [c.name for c in thinned] == [c.name for c in full] and all(c.passed for c in thinned)


def test_samples_beyond_the_contact_cap_update_the_estimate_unkept(press, monkeypatch):
    """Past MAX_CONTACT_SAMPLES in contact the samples still update the nodes' sums (E goes
    on narrowing) but are not kept; the grid is no longer refined, and the state says so."""
    monkeypatch.setattr(samples, "MAX_CONTACT_SAMPLES", 1000)
    est = OnlineEstimator(ModelSpec(TIP))
    states = _run(est, press.time, press.z, press.force, 100)
    contact = next(s for s in states if s.in_contact)
    assert est.n_kept <= contact.n + 1000 < press.n_points
    capped = [s for s in states if s.n_contact > 1000 + 100]
    assert capped and all(any(f.startswith("more than 1,000 samples in contact")
                              for f in s.flags) for s in capped)
    last = states[-1]
    assert last.n == press.n_points and last.n_contact == press.n_points - (contact.n -
                                                                           contact.n_contact)
    assert last.E.rel_half_width < capped[0].E.rel_half_width
    assert last.E.lo < 1.25e5 < last.E.hi
    assert est.model_checks()  # on the samples kept


def test_the_stream_reader_stays_within_the_backlog_of_a_slow_consumer(monkeypatch):
    """A recording piped in faster than the updates: the reader read it all ahead (~300 bytes
    a sample waiting: 240 MB for 400,000 piped into follow); now it reads at most MAX_BACKLOG
    samples beyond the batches handed over, and every sample still arrives, in order."""
    monkeypatch.setattr("palpbayes.online.stream.MAX_BACKLOG", 500)
    n, chunk = 20_000, 50
    read = [0]
    ahead = []
    handed = [0]
    lock = threading.Lock()

    def lines():
        yield "time_s,z_m,force_n\n"
        for i in range(n):
            with lock:
                read[0] += 1
                ahead.append(read[0] - handed[0])
            yield f"{i / RATE},{0.1 - i * 1e-7},0.0\n"

    got = []
    for k, batch in enumerate(batches(lines(), SampleParser(), chunk=chunk, timeout=None)):
        if k < 3:
            time.sleep(0.2)  # the consumer busy: the reader runs ahead
        got.append(batch.t)
        with lock:
            handed[0] += batch.size
    t = np.concatenate(got)
    assert t.size == n and np.all(np.diff(t) > 0)
    # the bound, the line being read, and a batch handed over but not yet counted here
    assert max(ahead) <= 500 + 1 + chunk


def test_a_stopped_consumer_releases_a_reader_at_the_backlog(monkeypatch):
    """When the consumer stops (a target reached) with the reader waiting at the backlog, the
    reader is let go: it reads the rest of the stream to its end, keeping none of it (so that
    a sender is not reset), instead of waiting forever."""
    monkeypatch.setattr("palpbayes.online.stream.MAX_BACKLOG", 100)
    done = threading.Event()

    def lines():
        yield "time_s,z_m,force_n\n"
        for i in range(5000):
            yield f"{i / RATE},0.1,0.0\n"
        done.set()

    stream = batches(lines(), SampleParser(), chunk=10, timeout=None)
    first = next(stream)
    time.sleep(0.2)  # the reader fills the backlog and waits
    stream.close()
    assert first.size == 10
    assert done.wait(30)  # a liveness bound, not a speed one
