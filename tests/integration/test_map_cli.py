"""``palpbayes simulate --map`` then ``palpbayes map``: whole traces to the lump, from the CLI."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.maps.run import NODE_COLUMNS
from palpbayes.sim.map import read_map_truth
from palpbayes.units import format_pressure


@pytest.fixture(scope="module")
def phantom(tmp_path_factory):
    folder = tmp_path_factory.mktemp("phantom") / "block"
    rc = main(["simulate", str(folder), "--map", "--grid", "9x9", "--step", "3e-3",
               "--lump-ratio", "20", "--lump-radius", "5e-3", "--lump-depth", "5.5e-3",
               "--lump-x", "12.5e-3", "--lump-y", "11.2e-3", "--heterogeneity", "0.03",
               "--seed", "4"])
    assert rc == 0
    return folder


@pytest.fixture(scope="module")
def mapped_run(phantom, tmp_path_factory):
    """The map folder and what the command printed."""
    out = tmp_path_factory.mktemp("map") / "out"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["map", str(phantom / "manifest.csv"), "--out", str(out), "--workers", "2",
                   "--no-progress"])
    assert rc == 0
    return out, buf.getvalue()


@pytest.fixture(scope="module")
def mapped(mapped_run):
    return mapped_run[0]


def test_the_console_tells_the_map_median_from_the_lump_models_background(mapped_run,
                                                                          phantom):
    """Two numbers once printed under one name ("background E"): the field's median over every
    node (a lump's included: higher than the block's modulus) and the lump model's background
    outside the lump, whose interval covers the simulated block's modulus."""
    text = mapped_run[1]
    truth = read_map_truth(phantom)["E_background_pa"]
    assert "map median E" in text and "a lump's included" in text
    line = next(ln for ln in text.splitlines() if "background E outside the lump" in ln)
    lump = pd.read_csv(mapped_run[0] / "lump.csv").set_index("quantity").loc["E_background_pa"]
    assert lump["lo"] <= truth <= lump["hi"], (lump, truth)
    assert format_pressure(lump["median"], 4) in line
    assert "background E " not in text.replace("background E outside", "")
    # --nu was not given: the note says nu was assumed only when the manifest has no nu column
    has_nu = "nu" in pd.read_csv(phantom / "manifest.csv", nrows=0).columns
    assert ("Poisson ratio not given" in text) is not has_nu


def test_every_map_flag_on_the_console_says_its_level(mapped_run):
    """A map's flags print as "info: ..." or "warning: ...", as settings.json stores them."""
    text = mapped_run[1]
    stored = json.loads((mapped_run[0] / "settings.json").read_text())["flags"]
    lines = [ln.strip() for ln in text.splitlines() if ln.startswith("  info: ")
             or ln.startswith("  warning: ")]
    assert "flag: " not in text and len(lines) == len(stored)
    for ln, f in zip(lines, stored, strict=True):
        assert ln == (f if f.startswith("info: ") else f"warning: {f}")


def test_map_writes_every_file_a_user_opens(mapped):
    import arviz as az
    from pypdf import PdfReader

    nodes = pd.read_csv(mapped / "map.csv")
    assert list(nodes.columns) == NODE_COLUMNS and len(nodes) == 81
    assert (nodes["n_traces"] == 1).all()
    assert np.all((0 <= nodes["p_stiffer"]) & (nodes["p_stiffer"] <= 1))
    assert np.all(nodes["E_lo_pa"] < nodes["E_mean_pa"]) and np.all(
        nodes["E_mean_pa"] < nodes["E_hi_pa"])
    points = pd.read_csv(mapped / "points.csv")
    assert len(points) == 81 and points["error"].isna().all()
    idata = az.from_netcdf(mapped / "map.nc")
    assert idata.posterior["log_E"].dims == ("chain", "draw", "y", "x")
    assert idata.posterior["log_E"].shape[2:] == (9, 9)
    np.testing.assert_allclose(idata.posterior["x"].values, np.arange(9) * 3e-3, atol=1e-12)
    # the map's own numbers are those draws: the node table is their summary
    logE = idata.posterior["log_E"].values.reshape(-1, 81)
    np.testing.assert_allclose(nodes["logE_mean"], logE.mean(axis=0), rtol=1e-12)
    lump_nc = az.from_netcdf(mapped / "lump.nc")
    assert "log_A" in lump_nc.posterior
    pages = [p.extract_text() for p in PdfReader(mapped / "map-report.pdf").pages]
    assert len(pages) == 6
    for want in ("summary", "Heat map", "Uncertainty map", "Probability map", "Profile",
                 "apparent peak ratio"):
        assert any(want in t for t in pages), want
    assert (mapped / "map.png").stat().st_size > 20_000
    # one name per number: the field's median is called that, the lump model's E_b background
    summary = " ".join(pages[0].split())
    assert "Background (median of the field)" not in summary
    assert "Map median E (the field's median over every node" in summary
    assert "background E away from the lump" in summary


def test_settings_record_the_poisson_ratio_the_points_used(phantom, tmp_path):
    """The manifest's nu (0.45 here) is the one every point is fitted with, and settings.json
    says so (it said the default 0.3)."""
    manifest = pd.read_csv(phantom / "manifest.csv")
    manifest["nu"] = 0.45
    path = phantom / "manifest-nu045.csv"  # beside the traces: the files are relative
    manifest.to_csv(path, index=False)
    out = tmp_path / "map"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["map", str(path), "--out", str(out), "--workers", "2", "--no-lump",
                     "--no-report", "--no-progress"]) == 0
    settings = json.loads((out / "settings.json").read_text())
    assert settings["points"]["nu"] == 0.45
    assert (pd.read_csv(out / "points.csv")["nu"] == 0.45).all()


def test_the_lump_is_found_where_it_is(mapped, phantom):
    truth = read_map_truth(phantom)
    lump = pd.read_csv(mapped / "lump.csv").set_index("quantity")
    d = math.hypot(lump.loc["x_m", "median"] - truth["x_m"],
                   lump.loc["y_m", "median"] - truth["y_m"])
    assert d <= truth["step_m"], f"centre {d * 1e3:.2f} mm from the truth"
    a = lump.loc["apparent_ratio"]
    assert a["lo"] <= truth["peak_apparent_ratio"] <= a["hi"], (a, truth["peak_apparent_ratio"])
    nodes = pd.read_csv(mapped / "map.csv")
    peak = nodes.loc[nodes["p_stiffer"].idxmax()]
    assert peak["p_stiffer"] > 0.8
    far = np.hypot(nodes["x_m"] - truth["x_m"], nodes["y_m"] - truth["y_m"]) > 10e-3
    assert nodes.loc[far, "p_stiffer"].max() < 0.5


def test_map_refuses_what_it_cannot_do(phantom, mapped, tmp_path, capsys):
    assert main(["map", str(phantom / "manifest.csv"), "--out", str(mapped)]) == 2
    assert "--force" in capsys.readouterr().err
    m = pd.read_csv(phantom / "manifest.csv").drop(columns=["x_m"])
    m["file"] = [str(phantom / f) for f in m["file"]]
    m.to_csv(tmp_path / "no_xy.csv", index=False)
    assert main(["map", str(tmp_path / "no_xy.csv"), "--out", str(tmp_path / "o"),
                 "--scheduler", "synchronous"]) == 2
    assert "x_m" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()  # refused before any folder is made
    assert main(["map", str(phantom / "manifest.csv"), "--out", str(tmp_path / "o2"),
                 "--threshold", "0.9"]) == 2
    assert "threshold" in capsys.readouterr().err


def test_a_failed_rerun_leaves_the_previous_map_as_it_was(phantom, mapped, monkeypatch):
    """--force writes into a staging folder and replaces the map only when the run succeeded."""
    import palpbayes.maps.run as run
    from palpbayes.errors import FitError

    before = {p.name: p.read_bytes() for p in mapped.iterdir()}

    def broken(*args, **kwargs):
        raise FitError("simulated failure after the fits")

    monkeypatch.setattr(run, "make_map", broken)
    assert main(["map", str(phantom / "manifest.csv"), "--out", str(mapped), "--force"]) == 1
    assert {p.name: p.read_bytes() for p in mapped.iterdir()} == before
    assert not [p for p in mapped.parent.iterdir() if "-partial-" in p.name]


# --- a robot log's manifest (issue 46 item 2) ------------------------------------------------

#: fit's options for the UR-style logs of _robot_log_map: time, TCP z in mm, force in N that
#: reads pressing as negative.
ROBOT_OPTIONS = ["--time-column", "timestamp", "--z-column", "actual_TCP_pose_2",
                 "--force-column", "fz", "--z-unit", "mm", "--force-sign", "-1"]
ROBOT_E = 60e3  # [Pa]


def _robot_log_map(folder, *, n=12, nx=4, step=2e-3, material=None):
    """A map manifest of n UR RTDE-style logs (timestamp [s], actual_TCP_pose_2 [mm], fz [N],
    pressing negative) on an nx-column grid starting at (0, 0), without a material column
    unless ``material`` is given (as a user writes one for a robot); returns its path."""
    from palpbayes.io.manifest import tip_columns
    from palpbayes.paper import PAPER_TIPS
    from palpbayes.sim import simulate_trace

    tip = PAPER_TIPS["paraboloid"]
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for k in range(n):
        tid = f"press{k:02d}"
        tr = simulate_trace(ROBOT_E, tip, thickness=0.02, rng=200 + k, approach=5e-4,
                            trace_id=tid, base=None)
        pd.DataFrame({"timestamp": tr.time, "actual_TCP_pose_2": tr.z * 1e3,
                      "fz": -tr.force}).to_csv(folder / f"{tid}.csv", index=False)
        rows.append({"trace_id": tid, "file": f"{tid}.csv", "tip": tip.kind,
                     **{c: v for c, v in tip_columns(tip).items() if not np.isnan(v)},
                     "x_m": (k % nx) * step, "y_m": (k // nx) * step,
                     **({} if material is None else {"material": material})})
    path = folder / "manifest.csv"
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_map_takes_fits_column_unit_and_sign_options():
    """One argparse group serves both commands: the same flags, defaults, choices and help."""
    from palpbayes.cli import build_parser

    sub = next(a for a in build_parser()._actions if hasattr(a, "choices")
               and isinstance(a.choices, dict) and "map" in a.choices).choices

    def column_options(parser):
        return {a.option_strings[0]: (a.dest, a.default, a.choices, a.help)
                for a in parser._actions
                if a.option_strings and a.option_strings[0].endswith(("-column", "-unit",
                                                                      "-sign"))}

    fit, mapped = column_options(sub["fit"]), column_options(sub["map"])
    assert set(fit) == {f"--{q}-{w}" for q in ("time", "z", "force") for w in ("column", "unit")
                        } | {"--force-sign", "--z-sign"}
    assert mapped == fit


def test_a_robot_log_manifest_maps_with_the_options_fit_takes(tmp_path, capsys):
    """A manifest of UR-style logs (no material column) maps with fit's --time-column,
    --z-unit and --force-sign, and map.csv writes the node at 0 as 0.0 (it wrote -2.7e-18)."""
    manifest = _robot_log_map(tmp_path / "robot")
    out = tmp_path / "robot-map"
    rc = main(["map", str(manifest), "--out", str(out), *ROBOT_OPTIONS, "--scheduler",
               "synchronous", "--no-lump", "--no-report", "--no-progress"])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    points = pd.read_csv(out / "points.csv")
    assert points["error"].isna().all() and len(points) == 12
    assert np.all(np.abs(points["E_median_pa"] / ROBOT_E - 1) < 0.05), points["E_median_pa"]
    nodes = pd.read_csv(out / "map.csv")
    assert sorted(set(nodes["x_m"])) == [0.0, 0.002, 0.004, 0.006]
    assert sorted(set(nodes["y_m"])) == [0.0, 0.002, 0.004]
    text = (out / "map.csv").read_text().splitlines()
    first = dict(zip(text[0].split(","), text[1].split(","), strict=True))
    assert (first["x_m"], first["y_m"]) == ("0.0", "0.0"), first
    settings = json.loads((out / "settings.json").read_text())["lattice"]
    assert (settings["x0_m"], settings["y0_m"], settings["step_m"]) == (0.0, 0.0, 0.002)
    import arviz as az

    post = az.from_netcdf(out / "map.nc").posterior
    assert post["x"].values.tolist() == [0.0, 0.002, 0.004, 0.006]
    assert post["y"].values.tolist() == [0.0, 0.002, 0.004]


def test_a_bad_column_is_reported_before_any_cluster_starts(tmp_path, capsys, monkeypatch):
    """Without the options, or with a misspelled column, map stops on the first file's header
    (naming the file, its row, the column and the option) before Dask is asked for a client,
    and makes no output folder (the manifest has a material column: only the columns are wrong)."""
    import palpbayes.cluster
    import palpbayes.maps.pertrace

    calls = []

    def no_cluster(*args, **kwargs):
        calls.append(args)
        raise AssertionError("a Dask client was asked for")

    monkeypatch.setattr(palpbayes.maps.pertrace, "dask_client", no_cluster)
    monkeypatch.setattr(palpbayes.cluster, "dask_client", no_cluster)
    manifest = _robot_log_map(tmp_path / "robot", material="silicone")
    out = tmp_path / "robot-map"
    rc = main(["map", str(manifest), "--out", str(out), "--workers", "2", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1, err
    assert str(manifest.parent / "press00.csv") in err and "row 1 (trace 'press00')" in err
    assert "11 other trace file(s) with the same header" in err
    assert "--time-column timestamp" in err and "--force-column fz" in err
    bad = [o if o != "fz" else "Fz" for o in ROBOT_OPTIONS]
    rc = main(["map", str(manifest), "--out", str(out), *bad, "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "column 'Fz' (given for force) is missing" in err, err
    assert "the file has timestamp, actual_TCP_pose_2, fz" in err
    assert calls == [] and not out.exists()


def test_the_python_door_makes_the_command_lines_map(phantom, mapped, tmp_path):
    """``pb.fit_map`` (issue 57): the same seed gives the command line's ``map.csv`` byte for
    byte from ``.summary()``, and ``.save`` writes the same files with the same tables."""
    import palpbayes as pb
    from palpbayes.maps.files import FIGURE, MAP, POINTS, REPORT

    m = pb.fit_map(phantom / "manifest.csv", seed=0, workers=2, progress=False)
    ours = tmp_path / "map.csv"
    m.summary().to_csv(ours, index=False)
    theirs = pd.read_csv(mapped / MAP)
    pd.testing.assert_frame_equal(pd.read_csv(ours), theirs)
    out = m.save(tmp_path / "py-map")
    for name in (MAP, POINTS):
        assert (out / name).read_bytes() == (mapped / name).read_bytes(), name
    assert (out / FIGURE).stat().st_size > 0 and (out / REPORT).stat().st_size > 0
    fig = m.plot()
    assert len(fig.axes) >= 4
    with pytest.raises(pb.errors.InputError, match="unknown option.*colour"):
        pb.fit_map(phantom / "manifest.csv", colour="red")
    with pytest.raises(pb.errors.InputError, match="AFM force map"):
        pb.fit_map(phantom / "manifest.csv", thickness=0.02)
