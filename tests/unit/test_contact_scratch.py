"""The hereditary integral's scratch arrays (contact/scratch.py): the same memory handed out
again per name and thread, a cap on what is kept, and no state carried from one call of
hereditary_contact to the next (nor between threads)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from palpbayes.contact import scratch as scratch_module
from palpbayes.contact.scratch import scratch
from palpbayes.contact.viscoelastic import (
    PowerLawKernel,
    PronyKernel,
    hereditary_contact,
    standard_linear_solid,
)

C_PARA = 4 * np.sqrt(0.01) / (3 * (1 - 0.3**2))


def test_same_name_same_memory_and_names_apart():
    a = scratch("test a", (3, 5))
    a[...] = 7.0
    again = scratch("test a", (5, 3))  # another shape on the same buffer
    assert np.shares_memory(a, again) and again.flags.c_contiguous and again.shape == (5, 3)
    b = scratch("test b", (3, 5), zero=True)
    assert not np.shares_memory(a, b) and np.all(b == 0.0)
    bigger = scratch("test a", (40, 40))  # grows: a new buffer under the name
    assert bigger.shape == (40, 40) and not np.shares_memory(a, bigger)


def test_requests_beyond_the_cap_get_fresh_arrays(monkeypatch):
    monkeypatch.setattr(scratch_module, "SCRATCH_BYTES", 8 * 1000)
    monkeypatch.setattr(scratch_module._BUFFERS, "arrays", {})
    kept = scratch("test kept", (100,))
    over = scratch("test over", (1000,), zero=True)
    assert np.all(over == 0.0)
    assert not np.shares_memory(over, scratch("test over", (1000,)))  # not kept
    assert np.shares_memory(kept, scratch("test kept", (100,)))
    assert sum(a.nbytes for a in scratch_module._BUFFERS.arrays.values()) <= 8 * 1000


def test_each_thread_has_its_own_buffers():
    here = scratch("test thread", (10,))
    there = []
    worker = threading.Thread(target=lambda: there.append(scratch("test thread", (10,))))
    worker.start()
    worker.join()
    assert not np.shares_memory(here, there[0])


def _cycle(n, top, seed):
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, n - 1) / 800.0)])
    d = np.interp(t / t[-1], [0.0, 0.45, 0.6, 1.0], [-0.1e-3, top, top, -0.5e-3])
    return t, d


@pytest.mark.parametrize("kernel", [PowerLawKernel(1e5, 0.3), standard_linear_solid(5e4, 5e4, 0.5),
                                    PronyKernel(2e4, (3e4, 3e4, 3e4, 1e4, 1e4),
                                                (1e-3, 0.05, 0.5, 5.0, 50.0))],
                         ids=["power law", "SLS", "Prony 5"])
def test_no_state_carried_between_calls(kernel):
    """A long cycle, then a short one with another shape of retract, then the long one again:
    the repeat is bit-identical to the first call, and to the same calls run in two threads
    at once (each its own scratch)."""
    long_, short = _cycle(3000, 3e-3, 1), _cycle(700, 1e-3, 2)
    first = hereditary_contact(*long_, C_PARA, 1.5, kernel)
    other = hereditary_contact(*short, C_PARA, 1.5, kernel)
    again = hereditary_contact(*long_, C_PARA, 1.5, kernel)
    np.testing.assert_array_equal(again.force, first.force)
    np.testing.assert_array_equal(again.t1, first.t1)
    results = {}

    def run(key, motion):
        for _ in range(3):
            results[key] = hereditary_contact(*motion, C_PARA, 1.5, kernel)

    threads = [threading.Thread(target=run, args=(key, motion))
               for key, motion in (("long", long_), ("short", short))]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    np.testing.assert_array_equal(results["long"].force, first.force)
    np.testing.assert_array_equal(results["short"].force, other.force)
    assert np.all(first.force[first.ting] >= 0) and first.ting.sum() > 100


def _poisoned(name, shape, zero=False):
    """A fresh array full of NaN (zeros when asked): a read of anything not written shows."""
    return np.zeros(shape) if zero else np.full(shape, np.nan)


@pytest.mark.parametrize("m", [1.0, 1.5, 2.0, 1.3])
@pytest.mark.parametrize("cycles", [1, 3])
def test_nothing_unwritten_is_read(m, cycles, monkeypatch):
    """Every scratch array replaced by a fresh NaN-filled one: force and t1 bit-identical, for
    the power law, the SLS, a 5-term Prony series and a Maxwell solid (E_inf = 0), one
    approach-hold-retract or three of them (several groups of Ting's rows)."""
    from palpbayes.contact import hereditary_steps, ting_rule, viscoelastic

    rng = np.random.default_rng(7)
    n = 900 * cycles
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, n - 1) / 800.0)])
    x = (t / t[-1] * cycles) % 1.0
    d = np.interp(x, [0.0, 0.45, 0.6, 1.0], [-0.1e-3, 2e-3, 2e-3, -0.5e-3])
    kernels = (PowerLawKernel(1e5, 0.3), standard_linear_solid(5e4, 5e4, 0.5),
               PronyKernel(2e4, (3e4, 3e4, 3e4, 1e4, 1e4), (1e-3, 0.05, 0.5, 5.0, 50.0)),
               PronyKernel(0.0, (5e4,), (0.2,)))
    plain = [hereditary_contact(t, d, C_PARA, m, k) for k in kernels]
    for module in (viscoelastic, hereditary_steps, ting_rule):
        monkeypatch.setattr(module, "scratch", _poisoned)
    for k, ref in zip(kernels, plain, strict=True):
        got = hereditary_contact(t, d, C_PARA, m, k)
        assert np.all(np.isfinite(got.force)) and got.ting.sum() > 100
        np.testing.assert_array_equal(got.force, ref.force)
        np.testing.assert_array_equal(got.t1, ref.t1)


def test_prony_inverse_where_the_branch_has_decayed():
    """A Maxwell solid (E_inf = 0) far beyond its tau: E(w) is a tiny positive number, not 0,
    so Newton still reaches the root; the target at a bound returns that bound (on [45, 50]
    the integral is 1 to the last bit: any w is a root, the upper bound is returned)."""
    k = PronyKernel(0.0, (1.0,), (1.0,))
    lo, hi = np.array([30.0, 45.0, 0.1]), np.array([40.0, 50.0, 3.0])
    np.testing.assert_allclose(k._inverse_integral(k.integral(hi), lo, hi), hi, rtol=1e-12)
    got = k._inverse_integral(k.integral(lo), lo, hi)
    np.testing.assert_allclose(got[[0, 2]], lo[[0, 2]], rtol=1e-12)
    assert k.integral(got[1]) == k.integral(lo[1])
    w = np.array([0.5, 1.7])
    np.testing.assert_allclose(k._inverse_integral(k.integral(w), np.zeros(2), np.full(2, 3.0)),
                               w, rtol=1e-12)
