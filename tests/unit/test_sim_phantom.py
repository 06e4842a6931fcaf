"""A map phantom pressed anywhere is the phantom ``simulate --map`` writes on its grid."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.errors import InputError
from palpbayes.inclusion import Inclusion
from palpbayes.io.trace_csv import read_trace
from palpbayes.sim.campaign import child_seed
from palpbayes.sim.map import default_inclusion, simulate_map
from palpbayes.sim.phantom import MapPhantom


def test_a_press_at_a_node_with_its_stream_is_that_nodes_trace(tmp_path):
    out = simulate_map(tmp_path / "m", seed=4, nx=4, ny=3, step=4e-3)
    ph = MapPhantom.from_map(out)
    inc = default_inclusion(4, 3, 4e-3)
    assert ph.inclusion == inc and ph.heterogeneity == 0.03
    truth = pd.read_csv(out / "truth.csv").set_index("trace_id")
    for j, i in ((0, 0), (1, 2), (2, 3)):
        tid = f"p{j:03d}_{i:03d}"
        gen = np.random.default_rng(child_seed(4, "map", j, i))
        tr = ph.press(i * 4e-3, j * 4e-3, gen=gen)
        assert tr.metadata["E_true"] == truth.loc[tid, "E_true_pa"]
        written = read_trace(out / "traces" / f"{tid}.csv")
        np.testing.assert_allclose(tr.force, written.force, rtol=1e-7, atol=1e-12)
        assert float(ph.apparent_modulus(i * 4e-3, j * 4e-3)) == pytest.approx(
            truth.loc[tid, "E_apparent_pa"], rel=1e-12)


def test_presses_are_reproducible_and_independent():
    ph = MapPhantom(inclusion=Inclusion(x=0.02, y=0.02, depth=6e-3, radius=5e-3, ratio=10))
    a, b = ph.press(0.02, 0.02, key=1), ph.press(0.02, 0.02, key=1)
    c = ph.press(0.02, 0.02, key=2)
    assert np.array_equal(a.force, b.force) and not np.array_equal(a.force, c.force)
    # over the lump the field is stiffer than the background
    assert ph.apparent_modulus(0.02, 0.02) > 1.1 * ph.apparent_modulus(0.0, 0.0)
    assert float(MapPhantom().apparent_modulus(0.01, 0.0)) == 50e3


def test_bad_phantoms_are_refused():
    with pytest.raises(InputError, match="reaches below"):
        MapPhantom(inclusion=Inclusion(x=0, y=0, depth=0.018, radius=0.005, ratio=2))
    with pytest.raises(InputError, match="finite"):
        MapPhantom().press(float("nan"), 0.0)
