"""The Python front door (palpbayes.api) against the command line: one code path, the same
numbers; what a Fit carries; bad sources and options named."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import palpbayes as pb
from palpbayes.cli import main
from palpbayes.errors import GeometryError, InputError


@pytest.fixture(scope="module")
def trace_file(tmp_path_factory):
    root = tmp_path_factory.mktemp("api")
    tr = pb.simulate_trace(120e3, pb.Tip("sphere", radius=0.01), nu=0.45, thickness=0.02,
                           rng=5, trace_id="trace")
    return pb.write_trace(tr, root / "trace.csv")


def test_fit_equals_the_command_line_field_by_field(trace_file, tmp_path):
    """The issue's case: pb.fit(path, tip, radius, nu, seed) and `palpbayes fit` with the same
    options (default engine, emcee) write byte-identical summary.csv files."""
    f = pb.fit(trace_file, tip="sphere", radius=0.01, nu=0.45, seed=1, method="both")
    f.save(tmp_path / "api")
    assert main(["fit", str(trace_file), "--tip", "sphere", "--radius", "0.01", "--nu", "0.45",
                 "--seed", "1", "--method", "both", "--out", str(tmp_path / "cli")]) == 0
    api = (tmp_path / "api" / "summary.csv").read_text()
    cli = (tmp_path / "cli" / "summary.csv").read_text()
    assert api == cli
    df = pd.read_csv(tmp_path / "cli" / "summary.csv")
    assert list(f.summary()["method"]) == list(df["method"]) == ["bayes", "lsq"]
    assert f.E == df.loc[0, "E_pa"] and f.interval == (df.loc[0, "E_lo_pa"],
                                                       df.loc[0, "E_hi_pa"])


def test_a_fit_carries_its_posterior_plot_and_words(trace_file):
    import arviz as az
    from matplotlib.figure import Figure

    f = pb.fit(trace_file, tip="sphere", radius=0.01, nu=0.45, engine="exact", seed=2)
    assert isinstance(f.plot(), Figure)
    s = az.summary(f.posterior, var_names=["E_star"])
    assert s.loc["E_star", "r_hat"] < 1.01
    assert repr(f).startswith("Fit('trace', bayes: E ")
    assert f.bayes is not None and f.lsq is not None and f.E_instron is None
    assert {c.name for c in f.checks} >= {"exponent", "ppc"}
    assert all(isinstance(n, str) and "; " not in n for n in f.notes)


def test_sources_a_trace_and_a_dataframe_give_the_file_s_numbers(trace_file):
    ref = pb.fit(trace_file, tip="sphere", radius=0.01, nu=0.45, engine="exact", seed=3)
    trace = pb.read(trace_file, tip="sphere", radius=0.01)
    frame = pd.read_csv(trace_file)
    for source in (trace, frame):
        other = pb.fit(source, tip="sphere", radius=0.01, nu=0.45, engine="exact", seed=3,
                       trace_id="trace") if isinstance(source, pd.DataFrame) else pb.fit(
            source, nu=0.45, engine="exact", seed=3)
        assert other.E == pytest.approx(ref.E, rel=1e-12)
        assert other.interval == pytest.approx(ref.interval, rel=1e-12)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"radius": 0.01}, GeometryError, "tip sizes given without a tip kind"),
    ({"tip": "sphere", "radius": 0.01, "curve": 2}, InputError, "curve= picks a curve"),
    ({"tip": "sphere", "radius": 0.01, "thickness": "unknown", "specimen": "0.05,0.05,0.02"},
     InputError, "contradicts --thickness unknown"),
    ({"tip": "sphere", "radius": 0.01, "nu": 0.3, "nu_range": (0.2, 0.4)}, InputError,
     "--nu or --nu-range"),
    ({"tip": "sphere", "radius": 0.01, "engine": "exact", "noise": "student"}, InputError,
     "--engine exact takes"),
    ({"tip": "sphere", "radius": 0.01, "method": "bayse"}, InputError,
     "unknown method 'bayse'; use one of bayes, lsq, both"),
    ({"tip": "sphere", "radius": 0.01, "method": "lsq", "engine": "emcees"}, InputError,
     "unknown engine 'emcees'"),
    ({"tip": "sphere", "radius": 0.01, "thickness": "abc"}, InputError,
     "thickness 'abc' is neither a thickness in metres nor 'unknown'"),
    ({"tip": "sphere", "radius": 0.01, "seed": -1}, InputError,
     "seed -1 must be a non-negative whole number"),
    ({"tip": "sphere", "radius": 0.01, "delimiter": ";", "nu": 0.45}, InputError, None),
])
def test_bad_options_are_named(trace_file, kwargs, error, match):
    if match is None:  # a reader option of a CSV reaches the reader (the file is comma-separated)
        with pytest.raises(error):
            pb.fit(trace_file, **kwargs)
        return
    with pytest.raises(error, match=match):
        pb.fit(trace_file, **kwargs)


def test_bad_sources_are_named(trace_file):
    with pytest.raises(InputError, match="takes a path, an IndentationTrace or a DataFrame"):
        pb.fit(np.zeros(3), tip="sphere", radius=0.01)
    frame = pd.read_csv(trace_file)
    for option in ({"curve": 1}, {"force_topic": "/ft"}, {"spring_constant": 0.1}):
        with pytest.raises(InputError, match="apply to a file, not to a DataFrame"):
            pb.fit(frame, tip="sphere", radius=0.01, **option)


def test_a_failed_fit_is_a_row_as_on_the_command_line(tmp_path):
    """The paper's least squares has no offset: a sensor reading -2 N before contact fails it.
    pb.fit records the failure in its row, as palpbayes fit does; strict=True raises."""
    from palpbayes.errors import FitError

    tr = pb.simulate_trace(120e3, pb.Tip("sphere", radius=0.01), nu=0.45, rng=6,
                           depth=2e-3, force_offset=-2.0, trace_id="offset")
    path = pb.write_trace(tr, tmp_path / "offset.csv")
    f = pb.fit(path, tip="sphere", radius=0.01, nu=0.45, method="lsq")
    assert np.isnan(f.E) and "fit_failed" in f.row["flag_codes"]
    assert repr(f).startswith("Fit('offset', lsq: E ")
    assert main(["fit", str(path), "--tip", "sphere", "--radius", "0.01", "--nu", "0.45",
                 "--method", "lsq", "--out", str(tmp_path / "cli")]) == 0
    f.save(tmp_path / "api")
    assert ((tmp_path / "api" / "summary.csv").read_text()
            == (tmp_path / "cli" / "summary.csv").read_text())
    with pytest.raises(FitError, match="the lsq fit failed in strict mode"):
        pb.fit(path, tip="sphere", radius=0.01, nu=0.45, method="lsq", strict=True)


def test_a_saved_fit_reads_back_as_a_results_folder(trace_file, tmp_path):
    f = pb.fit(trace_file, tip="sphere", radius=0.01, nu=0.45, engine="exact", seed=4)
    res = pb.load_results(f.save(tmp_path / "saved"))
    back = pb.reporting.load_fit(res, "trace")
    assert back.summary_row()["E_pa"] == f.E
    assert (tmp_path / "saved" / "posterior" / "trace.nc").is_file()


def test_top_level_names_resolve():
    for name in pb.__all__:
        assert getattr(pb, name) is not None, name
    assert "fit" in dir(pb) and pb.report.__name__ == "report"


def test_fit_campaign_without_a_folder_refuses_what_needs_one():
    import palpbayes as pb
    from palpbayes.errors import InputError

    with pytest.raises(InputError, match="resume needs the results folder"):
        pb.fit_campaign([], resume=True)
    with pytest.raises(InputError, match="give an out_dir its workers see"):
        pb.fit_campaign([], scheduler="tcp://127.0.0.1:8786")


def test_fit_campaign_without_a_folder_strict_names_the_failed_traces(tmp_path):
    from palpbayes.errors import FitError

    tr = pb.simulate_trace(120e3, pb.Tip("sphere", radius=0.01), nu=0.45, rng=6,
                           depth=2e-3, force_offset=-2.0, trace_id="offset")
    with pytest.raises(FitError, match=r"1 trace\(s\) failed in strict mode: offset \(see the "
                                       r"table a run without strict returns\)"):
        pb.fit_campaign([tr], options=pb.fit_options(method="lsq", strict=True), workers=1)
    table = pb.fit_campaign([tr], options=pb.fit_options(method="lsq"), workers=1)
    assert "fit_failed" in table.loc[0, "flag_codes"]


@pytest.fixture(scope="module")
def saved(trace_file, tmp_path_factory):
    """One fit with the defaults (no seed) saved by Fit.save, and `palpbayes fit` of the same
    file with the same options and no --seed."""
    root = tmp_path_factory.mktemp("saved")
    f = pb.fit(trace_file, tip="sphere", radius=0.01, nu=0.45, engine="exact", method="both")
    f.save(root / "api")
    assert main(["fit", str(trace_file), "--tip", "sphere", "--radius", "0.01", "--nu", "0.45",
                 "--engine", "exact", "--method", "both", "--out", str(root / "cli")]) == 0
    return f, root / "api", root / "cli"


def _files(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                  if p.is_file() and not p.relative_to(folder).as_posix().startswith(".partial"))


def test_save_writes_what_fit_out_writes_and_the_default_seeds_agree(saved):
    """Fit.save wrote summary.csv and the posterior only, against docs/api.md ('the layout of
    palpbayes fit --out'); pb.fit without a seed and fit without --seed give one summary."""
    _, api, cli = saved
    assert _files(api) == _files(cli) == ["posterior/trace.nc", "settings.json", "summary.csv",
                                          "traces.csv"]
    for name in ("settings.json", "traces.csv", "summary.csv"):
        assert (api / name).read_text() == (cli / name).read_text(), name


def test_a_saved_fit_loads_back_as_the_fit(saved, tmp_path):
    from matplotlib.figure import Figure

    f, api, cli = saved
    for source in (api, cli, cli / "posterior" / "trace.nc"):
        back = pb.load_fit(source)
        assert repr(back) == repr(f) and back.E == f.E and back.interval == f.interval
        assert back.summary().to_csv(index=False) == (cli / "summary.csv").read_text()
        np.testing.assert_array_equal(back.posterior.posterior["E"], f.posterior.posterior["E"])
        assert back.trace is None and back.methods == ["bayes", "lsq"]
        assert {c.name for c in back.checks} == {c.name for c in f.checks}
    assert isinstance(back.plot(), Figure)
    again = pb.Fit.load(back.save(tmp_path / "again"), trace_id="trace")
    assert again.summary().equals(back.summary())
    assert _files(tmp_path / "again") == _files(cli)
    assert main(["compare", str(tmp_path / "again")]) == 0


def test_reprs_say_the_result_in_a_line(saved):
    f, _, _ = saved
    text = repr(f.bayes)  # was ~9 kB: every array of the result
    assert len(text) < 300 and text.startswith("BayesResult('trace': E ")
    assert "(90 %), converged" in text and "2880 points" in text and "exact" in text
    assert repr(f).endswith(", 2880 points)")


def test_load_fit_names_what_is_wrong(saved, tmp_path):
    import shutil

    _, api, _ = saved
    two = shutil.copytree(api, tmp_path / "two")
    df = pd.read_csv(two / "summary.csv")
    pd.concat([df, df.assign(trace_id="other")]).to_csv(two / "summary.csv", index=False)
    for args, match in [
        ((tmp_path / "none",), "no such folder"),
        ((api / "summary.csv",), r"not a posterior \(\.nc\) file"),
        ((api / "posterior" / "x.nc",), "no such posterior file"),
        ((api / "posterior" / "trace.nc", "other"), "is the posterior of trace 'trace'"),
        ((api, "other"), r"no trace 'other' in its summary.csv \(it holds trace\)"),
        ((two,), r"holds 2 traces \(trace, other\); pick one with trace_id="),
        ((two, "other"), "no posterior for trace 'other'"),  # its row says it was fitted
    ]:
        with pytest.raises(InputError, match=match):
            pb.load_fit(*args)
    shutil.copy(api / "posterior" / "trace.nc", tmp_path / "trace.nc")
    with pytest.raises(InputError, match="not in the posterior/ folder of a results folder"):
        pb.load_fit(tmp_path / "trace.nc")
    assert pb.load_fit(two, "trace").E == pb.load_fit(api).E


def test_plot_draws_every_residual_and_least_squares_only_when_asked(tmp_path):
    """An untared sensor (0.2 N before contact): the least squares' residuals reach +202 mN
    and -55 mN; the panel showed -51..32 mN.  With method='bayes' the least-squares curve was
    drawn all the same."""
    tr = pb.simulate_trace(120e3, pb.Tip("sphere", radius=0.01), nu=0.45, rng=6,
                           depth=2e-3, force_offset=0.2, trace_id="offset")
    for method in ("both", "bayes"):
        fig = pb.fit(tr, nu=0.45, engine="exact", method=method).plot()
        fig.canvas.draw()
        labels = [lab for ax in fig.axes for lab in ax.get_legend_handles_labels()[1]]
        drawn = [ln.get_label() for ax in fig.axes for ln in ax.get_lines()]
        assert any("least squares" in s for s in labels) == (method == "both"), labels
        assert any("least squares" in s for s in drawn) == (method == "both"), drawn
        res = next(ax for ax in fig.axes if ax.get_title() == "Residuals")
        lo, hi = res.get_ylim()
        for ln in res.get_lines():
            y = np.asarray(ln.get_ydata(), float)
            assert lo <= np.nanmin(y) and np.nanmax(y) <= hi, (ln.get_label(), lo, hi)


def test_fit_campaign_takes_keywords_and_writes_the_command_line_s_summary(trace_file,
                                                                           tmp_path):
    from palpbayes.io.manifest import write_manifest

    manifest = write_manifest(pd.DataFrame({
        "trace_id": ["a", "b"], "file": [str(trace_file)] * 2, "material": ["gel"] * 2,
        "tip": ["sphere"] * 2, "radius_m": [0.01] * 2, "thickness_m": [0.02] * 2}),
        tmp_path / "manifest.csv")
    table = pb.fit_campaign(manifest, tmp_path / "api", nu=0.45, engine="exact", seed=4,
                            workers=1, progress=False)
    assert main(["fit", str(manifest), "--nu", "0.45", "--engine", "exact", "--seed", "4",
                 "--workers", "1", "--out", str(tmp_path / "cli"), "--no-progress"]) == 0
    cli = (tmp_path / "cli" / "summary.csv").read_bytes()
    assert (tmp_path / "api" / "summary.csv").read_bytes() == cli
    assert list(table["trace_id"]) == ["a", "b"] and table["E_pa"].notna().all()
    with pytest.raises(pb.errors.InputError, match="as keywords .*nu.* or as options="):
        pb.fit_campaign(manifest, tmp_path / "x", pb.fit_options(), nu=0.45)
    with pytest.raises(pb.errors.InputError, match="unknown option.*thickness.*a manifest gives"):
        pb.fit_campaign(manifest, tmp_path / "x", thickness=0.02)
    plans = []
    pb.fit_campaign(manifest, tmp_path / "y", engine="exact", workers=1, progress=False,
                    on_plan=lambda reused, todo: plans.append((reused, todo)))
    assert plans == [([], ["a", "b"])]
