"""Stiffness-map phantoms: folder, truth, reproducibility, validation, and the --map CLI."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.errors import DataFileError, InputError, OutputExistsError
from palpbayes.inclusion import (
    Inclusion,
    apparent_modulus,
    apparent_ratio,
    contact_radius,
    sensitivity,
)
from palpbayes.io.manifest import iter_traces, read_manifest
from palpbayes.io.trace_csv import write_trace
from palpbayes.lsq import fit_lsq
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import (
    child_seed,
    default_inclusion,
    read_map_truth,
    simulate_map,
    simulate_trace,
)

NX, NY, STEP, SEED = 5, 4, 3e-3, 7
A = contact_radius(PAPER_TIPS["paraboloid"], 2e-3)


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def phantom(tmp_path_factory):
    out = tmp_path_factory.mktemp("map") / "phantom"
    simulate_map(out, seed=SEED, nx=NX, ny=NY, step=STEP)
    return out


def test_layout_and_reproducible(phantom, tmp_path):
    files = _files(phantom)
    assert set(files) == ({"manifest.csv", "truth.csv", "truth_lump.json"}
                          | {f"traces/p{j:03d}_{i:03d}.csv" for j in range(NY) for i in range(NX)})
    again = simulate_map(tmp_path / "again", seed=SEED, nx=NX, ny=NY, step=STEP, workers=2)
    assert _files(again) == files  # same seed, byte-identical, whatever the workers
    other = simulate_map(tmp_path / "other", seed=SEED + 1, nx=NX, ny=NY, step=STEP)
    assert _files(other)["traces/p000_000.csv"] != files["traces/p000_000.csv"]


def test_manifest_positions_read_back(phantom):
    df = read_manifest(phantom / "manifest.csv")
    assert len(df) == NX * NY
    ids = [f"p{j:03d}_{i:03d}" for j in range(NY) for i in range(NX)]
    assert df["trace_id"].tolist() == ids
    assert df["x_m"].dtype == float and df["y_m"].dtype == float
    assert np.allclose(df["x_m"], np.tile(np.arange(NX) * STEP, NY), rtol=0, atol=1e-15)
    assert np.allclose(df["y_m"], np.repeat(np.arange(NY) * STEP, NX), rtol=0, atol=1e-15)
    assert set(df["tip"]) == {"paraboloid"} and set(df["nu"]) == {0.3}
    tr = next(iter_traces(df))
    assert tr.tip == PAPER_TIPS["paraboloid"] and tr.thickness == 0.02


def test_manifest_rejects_text_position(tmp_path, phantom):
    df = pd.read_csv(phantom / "manifest.csv").astype({"x_m": object})
    df["file"] = [str(phantom / f) for f in df["file"]]
    df.loc[2, "x_m"] = "3mm"
    df.to_csv(tmp_path / "manifest.csv", index=False)
    with pytest.raises(DataFileError, match=r"row 3 .*'x_m' holds '3mm'.*metres, e.g. 0.012"):
        read_manifest(tmp_path / "manifest.csv")


def test_truth_is_what_each_trace_was_simulated_with(phantom, tmp_path):
    """Redraw each point's stream as documented (ln E = ln E_app + h·N(0,1), then surface,
    offset, trace noise): the truth row and the trace file are reproduced exactly."""
    truth = pd.read_csv(phantom / "truth.csv")
    het = read_map_truth(phantom)["heterogeneity"]
    lump = default_inclusion(NX, NY, STEP)
    E_app = apparent_modulus(truth["x_m"], truth["y_m"], E_background=50e3, inclusion=lump,
                             contact_radius=A, thickness=0.02)
    assert truth["E_apparent_pa"].to_numpy() == pytest.approx(E_app, rel=1e-15)
    for k in (0, 7, NX * NY - 1):
        row = truth.iloc[k]
        j, i = divmod(k, NX)
        gen = np.random.default_rng(child_seed(SEED, "map", j, i))
        E = row["E_apparent_pa"] * math.exp(het * gen.standard_normal())
        zs = 0.1 + 1e-3 * gen.uniform(-1, 1)
        f0 = 5e-3 * gen.standard_normal()
        assert (row["E_true_pa"], row["z_surf_true_m"], row["force_offset_true_n"]) == (
            E, zs, f0)
        tr = simulate_trace(E, PAPER_TIPS["paraboloid"], z_surf=zs, thickness=0.02,
                            approach=5e-4, force_offset=f0, rng=gen, base=None)
        assert tr.metadata["E_true"] == row["E_true_pa"]
        write_trace(tr, tmp_path / "t.csv", float_format="%.8g")
        assert (tmp_path / "t.csv").read_bytes() == (phantom / "traces" /
                                                    f"{row['trace_id']}.csv").read_bytes()


def test_lump_truth(phantom):
    t = read_map_truth(phantom)
    lump = default_inclusion(NX, NY, STEP)
    assert t["has_lump"] and (t["x_m"], t["y_m"], t["depth_m"], t["radius_m"], t["ratio"]) == (
        lump.x, lump.y, lump.depth, lump.radius, lump.ratio)
    assert (t["nx"], t["ny"], t["step_m"], t["tip"], t["tip_radius_m"]) == (
        NX, NY, STEP, "paraboloid", 0.0117)
    assert t["contact_radius_m"] == pytest.approx(A) and t["tip_half_angle_deg"] is None
    # the lump sits off the grid's nodes
    assert min(abs(lump.x / STEP - round(lump.x / STEP)),
               abs(lump.y / STEP - round(lump.y / STEP))) > 0.1
    geo = {"radius": lump.radius, "depth": lump.depth, "contact_radius": A, "thickness": 0.02}
    peak = apparent_ratio(sensitivity(np.zeros(1), **geo), lump.ratio)[0]
    assert t["peak_apparent_ratio"] == pytest.approx(peak, rel=1e-12) and peak > 1.03
    half = apparent_ratio(sensitivity(np.array([t["apparent_fwhm_diameter_m"] / 2]), **geo),
                          lump.ratio)[0]
    assert half - 1 == pytest.approx((peak - 1) / 2, rel=1e-6)


def test_lsq_recovers_each_trace(phantom):
    """The package's own least squares recovers the modulus each trace was simulated with
    (the centre trace within 3 %, all within 6 %, no bias beyond 2 %)."""
    truth = pd.read_csv(phantom / "truth.csv").set_index("trace_id")
    lump = read_map_truth(phantom)
    err = {}
    for tr in iter_traces(phantom / "manifest.csv"):
        err[tr.trace_id] = fit_lsq(tr).E / truth.loc[tr.trace_id, "E_true_pa"] - 1
    d = np.hypot(truth["x_m"] - lump["x_m"], truth["y_m"] - lump["y_m"])
    centre = d.idxmin()
    assert abs(err[centre]) < 0.03
    e = np.array(list(err.values()))
    assert np.max(np.abs(e)) < 0.06 and abs(e.mean()) < 0.02


def test_heterogeneity_is_lognormal_about_the_field(tmp_path):
    """ln(E_true/E_app) ~ N(0, h²) point to point (no lump: E_app = E_b)."""
    out = simulate_map(tmp_path / "h", seed=3, nx=12, ny=10, inclusion=None,
                       heterogeneity=0.2)
    t = pd.read_csv(out / "truth.csv")
    assert np.all(t["E_apparent_pa"] == 50e3) and np.all(t["V"] == 0.0)
    z = np.log(t["E_true_pa"] / t["E_apparent_pa"])
    assert abs(z.mean()) < 3 * 0.2 / math.sqrt(len(z))
    assert z.std(ddof=1) == pytest.approx(0.2, rel=0.25)
    lump = read_map_truth(out)
    assert not lump["has_lump"] and lump["radius_m"] is None
    assert lump["peak_apparent_ratio"] == 1.0 and lump["apparent_fwhm_diameter_m"] is None


@pytest.mark.parametrize("kwargs, match", [
    ({"nx": 0}, "nx"),
    ({"step": -1e-3}, "grid step"),
    ({"E_background": 0.0}, "E_background"),
    ({"heterogeneity": -0.1}, "heterogeneity"),
    ({"inclusion": Inclusion(0.0, 0.0, depth=0.018, radius=5e-3, ratio=5.0)}, "thickness"),
    ({"workers": 0}, "workers"),
    ({"seed": -1}, "seed"),
    ({"noise_pp": -1.0}, "noise"),
    ({"depth": -1e-3}, "indentation depth"),
    ({"force_offset_sd": -1.0}, "force_offset_sd"),
    ({"float_format": "%q"}, "float_format"),
])
def test_bad_options_write_nothing(tmp_path, kwargs, match):
    out = tmp_path / "never"
    with pytest.raises(InputError, match=match):
        simulate_map(out, **{"nx": 3, "ny": 2, **kwargs})
    assert not out.exists()


def test_refuses_a_non_empty_folder(tmp_path):
    out = simulate_map(tmp_path / "m", nx=2, ny=2)
    with pytest.raises(OutputExistsError, match="not empty"):
        simulate_map(out, nx=2, ny=2)
    simulate_map(out, nx=1, ny=2, overwrite=True)  # a previous map's traces are replaced
    assert sorted(p.name for p in (out / "traces").iterdir()) == ["p000_000.csv",
                                                                  "p001_000.csv"]
    with pytest.raises(DataFileError, match="truth_lump.json"):
        read_map_truth(tmp_path)


def test_cli_map(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["simulate", str(out), "--map", "--grid", "4x3", "--seed", "2",
                 "--lump-ratio", "8", "--lump-depth", "6e-3", "--tip", "flat"]) == 0
    said = capsys.readouterr().out
    assert "12 traces (4 x 3 grid" in said and "apparent peak ratio" in said
    t = read_map_truth(out)
    assert (t["ratio"], t["depth_m"], t["tip"], t["nx"], t["ny"]) == (8.0, 6e-3, "flat", 4, 3)
    assert len(read_manifest(out / "manifest.csv")) == 12


@pytest.mark.parametrize("argv, match", [
    (["--map", "--grid", "4by3"], "NXxNY"),
    (["--map", "--grid", "0x3"], "NXxNY"),
    (["--grid", "4x3"], "--grid only apply with --map"),
    (["--map", "--repetitions", "2"], "--repetitions only apply to a campaign"),
    (["--map", "--no-lump", "--lump-ratio", "3"], "contradicts --lump-ratio"),
    (["--map", "--lump-depth", "1e-3"], "stick out"),
])
def test_cli_map_usage_errors(tmp_path, capsys, argv, match):
    out = tmp_path / "bad"
    try:
        code = main(["simulate", str(out), *argv])
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    assert code == 2
    assert match in capsys.readouterr().err
    assert not out.exists()
