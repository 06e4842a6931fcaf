"""``palpbayes map`` of a real AFM force map (issue 26, "Real force maps"): the curves of the
file become the map's rows with the file's positions, grid nodes without a curve and curves
that fail stay holes, the map of afmformats' extracted 2 × 2 JPK map runs end to end, and so
does the QI line with a lower contact threshold (--f-unc); the figures read in µm with the
holes marked.

The files are read from ``../shared/data/afm-files`` (see its README), never copied here."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pandas as pd
import pytest

from palpbayes.bayes.exact import exact_posterior
from palpbayes.campaign.fitjob import FitOptions, check_fittable
from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.errors import DataFileError
from palpbayes.io.afm import read_afm
from palpbayes.maps import afm_source
from palpbayes.maps.afm_source import NO_CURVE, afm_map_rows
from palpbayes.maps.lattice import lattice_from_positions
from palpbayes.maps.pertrace import PointOptions, fit_point

TIP = Tip("paraboloid", radius=5e-6)  # PyFMRheo's notebook; no AFM file records the tip
MAP2X2 = "fmt-jpk-fd_map2x2_extracted.jpk-force-map"
QI = "fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data"
WORKSHOP = "fmt-afm-workshop-fd_mapping_16_2018-08-01_13.07.zip"
PYFMRHEO = "pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map"
#: afmformats' own test values for the Workshop map (the file records neither)
WORKSHOP_META = {"spring constant": 20.0, "sensitivity": 0.01e-6}


@pytest.fixture(scope="module")
def afm_files():
    from conftest import find_shared_data

    return find_shared_data("afm-files", files=[MAP2X2, QI, WORKSHOP, PYFMRHEO])


@pytest.mark.parametrize("name, meta, n_holes", [
    (MAP2X2, None, 96), (QI, None, 0), (WORKSHOP, WORKSHOP_META, 0), (PYFMRHEO, None, 0)])
def test_every_curve_is_a_row_at_the_position_afmformats_reads(afm_files, name, meta, n_holes):
    import afmformats

    rows = afm_map_rows(afm_files / name, TIP, meta_override=meta)
    raw = afmformats.load_data(afm_files / name, meta_override=meta or {})
    curves = rows[rows["curve_index"] >= 0]
    assert len(curves) == len(raw) and (curves["error"] == "").all()
    assert (rows["curve_index"] < 0).sum() == n_holes == len(rows) - len(raw)
    np.testing.assert_array_equal(curves["curve_index"], np.arange(len(raw)))
    np.testing.assert_array_equal(curves["x_m"], [c.metadata["position x"] for c in raw])
    np.testing.assert_array_equal(curves["y_m"], [c.metadata["position y"] for c in raw])
    if "grid index x" in raw[0].metadata:
        np.testing.assert_array_equal(curves["grid_ix"], [c.metadata["grid index x"]
                                                           for c in raw])
    assert (rows["tip"] == "paraboloid").all() and (rows["radius_m"] == 5e-6).all()


def test_the_pyfmrheo_map_is_a_4_by_4_lattice_of_5_um(afm_files):
    rows = afm_map_rows(afm_files / PYFMRHEO, TIP)
    lat, node = lattice_from_positions(rows["x_m"].to_numpy(), rows["y_m"].to_numpy())
    assert (lat.nx, lat.ny) == (4, 4) and lat.step == pytest.approx(5e-6, rel=1e-6)
    assert sorted(node) == list(range(16))


def test_the_extracted_2x2_map_keeps_its_grid_and_its_96_missing_curves_as_holes(afm_files):
    """afmformats' 2 × 2 map is the four corners of a 10 × 10 JPK grid of 60 µm steps (grid
    size 600 µm): the missing 96 nodes stay on the lattice as holes, at their grid position."""
    rows = afm_map_rows(afm_files / MAP2X2, TIP)
    lat, node = lattice_from_positions(rows["x_m"].to_numpy(), rows["y_m"].to_numpy())
    assert (lat.nx, lat.ny) == (10, 10) and lat.step == pytest.approx(60e-6, rel=1e-3)
    assert sorted(node) == list(range(100))
    holes = rows[rows["curve_index"] < 0]
    assert holes["error"].str.startswith(NO_CURVE).all()
    assert set(zip(rows.loc[rows["curve_index"] >= 0, "grid_ix"],
                   rows.loc[rows["curve_index"] >= 0, "grid_iy"], strict=True)) == {
        (0, 0), (9, 0), (9, 9), (0, 9)}
    # a hole's node is its grid index
    np.testing.assert_array_equal(node[holes.index] % 10, holes["grid_ix"].astype(int))
    np.testing.assert_array_equal(node[holes.index] // 10, holes["grid_iy"].astype(int))


def test_files_that_are_not_maps_are_named_with_what_to_do(afm_files, shared_data, monkeypatch):
    single = afm_files / "fmt-jpk-fd_spot3-0192.jpk-force"
    with pytest.raises(DataFileError, match="one curve.*palpbayes fit"):
        afm_map_rows(single, TIP)
    with pytest.raises(DataFileError, match="spring-constant"):
        afm_map_rows(afm_files / WORKSHOP, TIP)  # the Workshop map lacks k and sensitivity
    real = afm_source.curve_metadata
    monkeypatch.setattr(afm_source, "curve_metadata",
                        lambda c: {k: v for k, v in real(c).items() if k != "y_m"})
    with pytest.raises(DataFileError, match=f"{PYFMRHEO}.*curve 0 has no position"):
        afm_map_rows(afm_files / PYFMRHEO, TIP)
    monkeypatch.setattr(afm_source, "curve_metadata",  # positions in micrometres
                        lambda c: {**real(c), "x_m": real(c)["x_m"] * 1e6})
    with pytest.raises(DataFileError, match="span .* not metres"):
        afm_map_rows(afm_files / PYFMRHEO, TIP)


def test_a_curve_that_fails_and_a_hole_are_rows_with_their_error(afm_files):
    rows = afm_map_rows(afm_files / MAP2X2, TIP)
    opts = PointOptions(fit=FitOptions(nu=0.5, engine="exact", layer="off"))
    bad = rows.iloc[0].copy()
    bad["curve_index"] = 7  # the file has 4 curves
    out = fit_point(bad, opts)
    assert MAP2X2 in out["error"] and "no curve 7" in out["error"]
    assert np.isnan(out["E_median_pa"]) and out["x_m"] == bad["x_m"]
    hole = fit_point(rows[rows["curve_index"] < 0].iloc[0], opts)
    assert hole["error"].startswith(NO_CURVE) and np.isnan(hole["logE_mean"])


def test_qi_curves_fail_by_default_saying_why_and_which_option(afm_files, tmp_path, capsys):
    """QI's 4 curves indent ~35 nm: at the default F_unc (6 sd of the baseline, 74 pN) only
    2-3 samples lie past the onset, every fit fails, and the map stops with status 2 naming
    the threshold and --f-unc (nothing written)."""
    rc = main(["map", str(afm_files / QI), "--tip", "paraboloid", "--radius", "5e-6",
               "--out", str(tmp_path / "qi"), "--scheduler", "synchronous", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and QI in err
    assert all(s in err for s in ("got 0 of 4", "sample(s) in contact", "F_unc = 74 pN",
                                  "lower --f-unc")), err
    assert not (tmp_path / "qi").exists()


def _map_cli(path, out, *extra: str) -> tuple:
    """``palpbayes map PATH`` with PyFMRheo's tip and nu, in this process: (out, stdout)."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["map", str(path), "--tip", "paraboloid", "--radius", "5e-6", "--nu", "0.5",
                   *extra, "--out", str(out), "--scheduler", "synchronous", "--no-progress"])
    assert rc == 0
    return out, buf.getvalue()


@pytest.fixture(scope="module")
def mapped_qi(afm_files, tmp_path_factory):
    """The QI line mapped with F_unc = 20 pN (about 1.7 sd of its baseline noise, 11-12 pN)."""
    return _map_cli(afm_files / QI, tmp_path_factory.mktemp("afm") / "qi", "--f-unc", "2e-11")


def test_the_qi_line_maps_end_to_end_with_a_lower_contact_threshold(mapped_qi):
    out, text = mapped_qi
    for name in ("map.csv", "points.csv", "map.nc", "map.png", "map-report.pdf"):
        assert (out / name).stat().st_size > 0, name
    points = pd.read_csv(out / "points.csv", keep_default_na=False, na_values=[""])
    assert len(points) == 4 and points["error"].isna().all()
    # a soft specimen: kPa, each point's interval wide (a few samples in contact)
    assert ((points["E_median_pa"] > 500) & (points["E_median_pa"] < 5e3)).all()
    assert (points["E_hi_pa"] / points["E_lo_pa"] > 1.5).all()
    assert (points["depth_m"] < 100e-9).all()
    nodes = pd.read_csv(out / "map.csv")
    assert len(nodes) == 4 and set(nodes["iy"]) == {0} and (nodes["n_traces"] == 1).all()
    assert "mapped 4 of 4 palpations on a 4 x 1 lattice (step 78.1 nm)" in text
    assert "the palpations lie on one line (4 × 1 nodes)" in text


def test_the_qi_lines_figure_is_a_strip_in_micrometres(mapped_qi):
    from palpbayes.plots.maps import plot_map

    nodes = pd.read_csv(mapped_qi[0] / "map.csv")
    fig = plot_map(nodes)
    images = [ax for ax in fig.axes if ax.images]
    assert len(images) == 3
    for ax in images:
        assert ax.images[0].get_array().shape == (1, 4)
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [µm]", "y [µm]")


def test_the_2x2_maps_figure_reads_in_micrometres_and_marks_its_96_holes(mapped_2x2):
    from palpbayes.plots.maps import HOLE_LABEL, plot_map_panel

    nodes = pd.read_csv(mapped_2x2[0] / "map.csv")
    ax = plot_map_panel(nodes, "mean").axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [µm]", "y [µm]")
    (holes,) = [ln for ln in ax.get_lines() if ln.get_label() == HOLE_LABEL]
    x, y = holes.get_data()
    assert len(x) == 96
    corners = {(0, 0), (9, 0), (9, 9), (0, 9)}
    step = 60.0  # µm
    x0, y0 = nodes["x_m"].min() * 1e6, nodes["y_m"].min() * 1e6
    got = {(round((a - x0) / step), round((b - y0) / step)) for a, b in zip(x, y, strict=True)}
    assert len(got) == 96 and not got & corners
    assert HOLE_LABEL in [t.get_text() for t in ax.get_legend().get_texts()]


@pytest.fixture(scope="module")
def mapped_2x2(afm_files, tmp_path_factory):
    return _map_cli(afm_files / MAP2X2, tmp_path_factory.mktemp("afm") / "map2x2")


def test_the_2x2_map_writes_its_files_with_holes_and_no_lump(mapped_2x2):
    out, text = mapped_2x2
    for name in ("map.csv", "points.csv", "map.nc", "map.png", "map-report.pdf",
                 "settings.json"):
        assert (out / name).stat().st_size > 0, name
    assert not (out / "lump.csv").exists()
    points = pd.read_csv(out / "points.csv", keep_default_na=False, na_values=[""])
    assert len(points) == 100
    fitted = points["error"].isna()
    assert fitted.sum() == 4 and points.loc[~fitted, "error"].str.startswith(NO_CURVE).all()
    nodes = pd.read_csv(out / "map.csv")
    corners = {(0, 0), (9, 0), (9, 9), (0, 9)}
    has = nodes["n_traces"] == 1
    assert set(zip(nodes.loc[has, "ix"], nodes.loc[has, "iy"], strict=True)) == corners
    assert (nodes.loc[~has, "n_traces"] == 0).all()
    assert "mapped 4 of 100 palpations on a 10 x 10 lattice" in text
    assert "only 4 fitted points" in text and "96 of 100 grid nodes have no curve" in text
    assert "lump model off" in text


def test_the_2x2_maps_point_is_the_exact_fit_of_the_same_curve(mapped_2x2, afm_files):
    """Each point's E: the exact engine on the curve read on its own (read_afm, curve i)."""
    points = pd.read_csv(mapped_2x2[0] / "points.csv").iloc[:4]
    opts = FitOptions(nu=0.5, engine="exact", layer="off")
    for i in (0, 3):
        (trace,) = read_afm(afm_files / MAP2X2, tip=TIP, curves=[i])
        data = check_fittable(trace, opts)
        post = exact_posterior(data, opts.priors.for_trace(data, opts.noise, opts.baseline))
        d = post.draws(np.random.default_rng(5), 2000)
        E = np.median(data.model.to_E(d["E_star"]))
        assert points.loc[i, "x_m"] == trace.metadata["x_m"]
        assert points.loc[i, "E_median_pa"] == pytest.approx(E, rel=0.01)


@pytest.mark.slow
def test_the_2x2_maps_point_agrees_with_palpbayes_fit(mapped_2x2, afm_files, tmp_path):
    """The map's per-point E against ``palpbayes fit --curve 0`` with the same tip, nu and
    engine: its statistical E (the map leaves out the systematic budget, common to all
    points)."""
    out = tmp_path / "fit"
    with contextlib.redirect_stdout(io.StringIO()):
        main(["fit", str(afm_files / MAP2X2), "--curve", "0", "--tip", "paraboloid",
              "--radius", "5e-6", "--nu", "0.5", "--engine", "exact", "--half-space",
              "--method", "bayes", "--workers", "1", "--out", str(out), "--no-progress"])
    fit = pd.read_csv(out / "summary.csv").iloc[0]
    point = pd.read_csv(mapped_2x2[0] / "points.csv").iloc[0]
    assert point["E_median_pa"] == pytest.approx(fit["E_stat_pa"], rel=0.01)
    assert point["E_lo_pa"] == pytest.approx(fit["E_stat_lo_pa"], rel=0.02)
    assert point["E_hi_pa"] == pytest.approx(fit["E_stat_hi_pa"], rel=0.02)


def test_inspect_reads_the_workshop_zip_and_says_what_it_lacks(afm_files, capsys):
    """afmformats reads the AFM Workshop zip only with k and the sensitivity; inspect shows its
    16 curves and their positions anyway and names the options a map needs."""
    assert main(["inspect", str(afm_files / WORKSHOP)]) == 0
    out = capsys.readouterr().out
    assert "AFM file, 16 curve(s) (force-distance)" in out
    assert "curve 0: approach 391, retract 391 points  at x = 1 µm, y = 2 µm" in out
    assert "--spring-constant" in out and "map FILE --tip" in out


def test_the_tip_is_required_for_an_afm_map_and_refused_for_a_manifest(afm_files, tmp_path,
                                                                       capsys):
    rc = main(["map", str(afm_files / PYFMRHEO), "--out", str(tmp_path / "a")])
    err = capsys.readouterr().err
    assert rc != 0 and "needs --tip" in err and PYFMRHEO in err
    rc = main(["map", str(tmp_path / "manifest.csv"), "--tip", "sphere", "--thickness", "1e-3",
               "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err
    assert rc != 0 and "--tip, --thickness: for an AFM force map" in err


def test_fit_takes_the_calibration_an_afm_file_lacks_with_maps_options(afm_files, tmp_path):
    """``fit`` and ``replay`` read the Workshop zip with --spring-constant/--sensitivity/
    --sample-rate, defined once (cli.options.add_afm_meta_options) for them and ``map``."""
    from palpbayes.cli import build_parser
    from palpbayes.cli.options import traces_from_args

    parser = build_parser()
    flags = ["--spring-constant", "20", "--sensitivity", "1e-8", "--sample-rate", "1000"]
    args = parser.parse_args(["fit", str(afm_files / WORKSHOP), "--curve", "3", "--tip",
                              "paraboloid", "--radius", "5e-6", *flags, "--out", "x"])
    (trace,) = traces_from_args(args)
    (want,) = read_afm(afm_files / WORKSHOP, tip=TIP, curves=[3],
                       meta_override={**WORKSHOP_META, "rate approach": 1000.0})
    np.testing.assert_array_equal(trace.force, want.force)
    np.testing.assert_array_equal(trace.z, want.z)
    helps = {}
    for command in ("fit", "replay", "map"):
        sub = parser._subparsers._group_actions[0].choices[command]
        helps[command] = {a.option_strings[0]: a.help for a in sub._actions
                          if a.option_strings and a.option_strings[0] in flags[::2]}
    assert helps["fit"] == helps["replay"] == helps["map"] and len(helps["fit"]) == 3
    with pytest.raises(DataFileError, match="spring-constant"):  # the file lacks k
        traces_from_args(parser.parse_args(["fit", str(afm_files / WORKSHOP), "--tip",
                                            "paraboloid", "--radius", "5e-6", "--out", "x"]))


def test_fit_of_a_workshop_curve_runs_and_the_options_are_refused_elsewhere(
        afm_files, tmp_path, capsys):
    out = tmp_path / "ws"
    with contextlib.redirect_stdout(io.StringIO()):
        rc = main(["fit", str(afm_files / WORKSHOP), "--curve", "3", "--tip", "paraboloid",
                   "--radius", "5e-6", "--nu", "0.5", "--engine", "exact", "--half-space",
                   "--no-model-form", "--spring-constant", "20", "--sensitivity", "1e-8",
                   "--sample-rate", "1000", "--workers", "1", "--out", str(out),
                   "--no-progress"])
    assert rc == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert 300e3 < row["E_pa"] < 600e3  # the map's 431 kPa (docs/reference.md), one curve
    table = tmp_path / "t.csv"
    pd.DataFrame({"time_s": [0.0, 1.0], "z_m": [0.0, -1e-3], "force_n": [0.0, 1.0]}).to_csv(
        table, index=False)
    rc = main(["fit", str(table), "--tip", "sphere", "--radius", "0.01", "--sensitivity",
               "1e-8", "--out", str(tmp_path / "t")])
    assert rc == 2 and "--sensitivity apply to AFM files only" in capsys.readouterr().err
    rc = main(["fit", str(afm_files / WORKSHOP), "--tip", "paraboloid", "--radius", "5e-6",
               "--spring-constant", "-1", "--out", str(tmp_path / "n")])
    assert rc == 2 and "--spring-constant -1.0 must be a positive" in capsys.readouterr().err
