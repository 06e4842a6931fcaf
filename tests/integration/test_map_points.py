"""Per-point fits of a map on Dask (palpbayes.maps.pertrace)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.errors import InputError
from palpbayes.io.manifest import read_manifest, tip_columns, write_manifest
from palpbayes.io.trace_csv import write_trace
from palpbayes.maps.pertrace import POINT_COLUMNS, PointOptions, fit_point, fit_points
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

TIP = PAPER_TIPS["paraboloid"]


def _manifest(folder, moduli, *, no_contact=()):
    """A 3-column row of traces with the given moduli; indices in no_contact never touch."""
    (folder / "traces").mkdir()
    rows = []
    for k, E in enumerate(moduli):
        tid = f"p{k:02d}"
        tr = simulate_trace(E, TIP, thickness=0.02, rng=100 + k, approach=5e-4, trace_id=tid,
                            base=None)
        if k in no_contact:  # the same motion, sensor noise only: the tip never touched
            noise = np.random.default_rng(k).normal(0.0, 8e-3, tr.z.size)
            pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": noise}).to_csv(
                folder / "traces" / f"{tid}.csv", index=False)
        else:
            write_trace(tr, folder / "traces" / f"{tid}.csv")
        rows.append({"trace_id": tid, "file": f"traces/{tid}.csv", "specimen": "b",
                     "material": "b", "tip": TIP.kind, **tip_columns(TIP), "thickness_m": 0.02,
                     "repetition": 1, "rest_time_s": np.nan, "x_m": (k % 3) * 2e-3,
                     "y_m": (k // 3) * 2e-3})
    write_manifest(pd.DataFrame(rows), folder / "manifest.csv")
    return read_manifest(folder / "manifest.csv")


def test_fit_point_recovers_the_modulus_within_its_interval(tmp_path):
    m = _manifest(tmp_path, [40e3, 80e3, 160e3])
    opts = PointOptions(draws=2000)
    for k, E in enumerate([40e3, 80e3, 160e3]):
        r = fit_point(m.iloc[k], opts, k)
        assert set(r) == set(POINT_COLUMNS) and r["error"] == ""
        z = (r["logE_mean"] - np.log(E)) / r["logE_sd"]
        assert abs(z) < 3.5, (E, r)
        assert r["E_lo_pa"] < r["E_median_pa"] < r["E_hi_pa"]
        assert abs(r["E_lsq_pa"] / E - 1) < 0.02
        assert 1.5e-3 < r["depth_m"] < 2.5e-3  # 10 % of 20 mm
        assert 1e-4 < r["logE_sd"] < 0.02


def test_unfittable_trace_gives_an_error_row_not_an_exception(tmp_path):
    m = _manifest(tmp_path, [50e3, 50e3], no_contact=(1,))
    r = fit_point(m.iloc[1], PointOptions(), 1)
    assert "contact" in r["error"].lower()
    assert np.isnan(r["logE_mean"]) and r["x_m"] == pytest.approx(2e-3)


def test_dask_local_cluster_matches_the_synchronous_run(tmp_path):
    m = _manifest(tmp_path, [50e3, 60e3, 70e3, 80e3, 90e3])
    done = []
    sync = fit_points(m, scheduler="synchronous", chunk=2, progress=False, on_done=done.append)
    assert done[-1] == 5
    dist = fit_points(m, workers=2, chunk=2, progress=False)
    assert list(dist["trace_id"]) == list(m["trace_id"])  # manifest order, whatever finished first
    pd.testing.assert_frame_equal(sync, dist)
    assert np.all(np.diff(sync["logE_mean"]) > 0)


def test_map_needs_positions_and_exact_engine_noise(tmp_path):
    m = _manifest(tmp_path, [50e3])
    with pytest.raises(InputError, match="x_m"):
        fit_points(m.drop(columns="x_m"), scheduler="synchronous")
    from palpbayes.campaign.fitjob import FitOptions

    with pytest.raises(InputError, match="exact engine"):
        PointOptions(fit=FitOptions(noise="student"))


def test_unreachable_scheduler_is_a_clear_error(tmp_path, monkeypatch):
    import palpbayes.cluster as cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", "2s")
    m = _manifest(tmp_path, [50e3])
    with pytest.raises(InputError, match="Dask scheduler"):
        fit_points(m, scheduler="tcp://127.0.0.1:9", progress=False)


def test_local_cluster_listens_on_loopback_and_survives_a_busy_8787(tmp_path):
    """The map's LocalCluster binds to 127.0.0.1 and puts its HTTP server on a free port, so
    a dashboard or another cluster on distributed's default port 8787 does not stop it (it
    did: "Port 8787 is already in use", an error under this suite's warnings-as-errors)."""
    import socket

    from palpbayes.cluster import dask_client

    busy = socket.socket()
    try:
        busy.bind(("127.0.0.1", 8787))
        busy.listen()
    except OSError:  # 8787 already taken by something else: the same situation
        pass
    try:
        client = dask_client(None, 1)
        try:
            assert client.scheduler.address.startswith("tcp://127.0.0.1:")
            assert client.submit(abs, -3).result() == 3
            info = client.scheduler_info()
            assert all(w.startswith("tcp://127.0.0.1:") for w in info["workers"])
        finally:
            cluster = client._palpbayes_cluster
            client.close()
            cluster.close()
    finally:
        busy.close()
