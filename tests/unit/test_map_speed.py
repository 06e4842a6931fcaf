"""The map's fast paths give what the plain paths give: the trace writer (the bytes pandas'
to_csv wrote), the chunk's one read of an AFM file (the traces), the task size of a small
map."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.contact import Tip
from palpbayes.io.atomic import write_csv_atomic
from palpbayes.io.trace_csv import write_trace
from palpbayes.maps.afm_source import afm_map_rows, load_point_trace
from palpbayes.maps.pertrace import CHUNK, _read_afm_curves, auto_chunk
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim.trace import simulate_trace
from palpbayes.trace import SEGMENTS

TIP = Tip("paraboloid", radius=5e-6)
WORKSHOP = "fmt-afm-workshop-fd_mapping_16_2018-08-01_13.07.zip"
WORKSHOP_META = {"spring constant": 20.0, "sensitivity": 0.01e-6, "rate approach": 1000.0}


@pytest.mark.parametrize("float_format", ["%.8g", "%.10g", "%.17g", "%.3f", "%.6e"])
def test_write_trace_writes_the_bytes_pandas_wrote(tmp_path, float_format):
    for k in range(5):
        g = np.random.default_rng(k)
        trace = simulate_trace(float(np.exp(g.uniform(7, 14))), PAPER_TIPS["paraboloid"],
                               nu=0.45, z_surf=0.1 + g.uniform(-1e-3, 1e-3), thickness=0.02,
                               depth=2e-3, approach=5e-4, noise_pp=g.uniform(0, 0.1),
                               force_offset=5e-3 * g.normal(), rng=g, trace_id="t", base=None,
                               hold=0.5 * k, retract=k % 2 == 1)
        df = pd.DataFrame({"time_s": trace.time, "z_m": trace.z, "force_n": trace.force})
        if trace.segment is not None:
            df["segment"] = np.asarray(SEGMENTS, dtype=object)[trace.segment]
        write_csv_atomic(df, tmp_path / "pandas.csv", float_format=float_format)
        write_trace(trace, tmp_path / "ours.csv", float_format=float_format)
        assert (tmp_path / "ours.csv").read_bytes() == (tmp_path / "pandas.csv").read_bytes()


def test_a_small_map_gives_every_worker_two_tasks_and_a_large_one_full_chunks():
    assert auto_chunk(16, 2) == 4
    assert auto_chunk(3, 8) == 1
    assert auto_chunk(10_000, 2) == CHUNK


def test_a_chunk_reads_its_afm_curves_once_and_gets_the_traces_read_one_by_one():
    from conftest import find_shared_data

    path = find_shared_data("afm-files", files=[WORKSHOP]) / WORKSHOP
    rows = afm_map_rows(path, TIP, meta_override=WORKSHOP_META)
    series = [pd.Series(r) for r in rows.iloc[[0, 3, 7]].to_dict("records")]
    got = _read_afm_curves(series, {"meta_override": WORKSHOP_META})
    assert sorted(got) == [0, 1, 2]
    for k, row in enumerate(series):
        one = load_point_trace(row, meta_override=WORKSHOP_META)
        assert got[k].trace_id == one.trace_id
        for name in ("time", "z", "force"):
            np.testing.assert_array_equal(getattr(got[k], name), getattr(one, name))
    # a hole is not read, and a lone curve is left to fit_point
    assert _read_afm_curves(series[:1], {"meta_override": WORKSHOP_META}) == {}
