"""A re-run of ``palpbayes report CAMPAIGN`` into the same results folder (issue 58, item 2).

A fit is reused only when its inputs are unchanged (the numbers read from the trace's file,
its manifest row, the options, the palpbayes version); the others are refitted, everything
downstream (summary, pooling, comparison) follows, and the console says what was reused.
A tiny campaign (one foam, not one of the paper's: no gap table; one tip, two traces,
infinitely wide layers: no twin to solve) with the exact engine keeps each run short; the
console is read from ``palpbayes report``, the other cases through
:func:`palpbayes.campaign.pipeline.run_pipeline` (no PDF).
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil

import pandas as pd
import pytest

from palpbayes import outputs as layout
from palpbayes.campaign.pipeline import run_pipeline
from palpbayes.cli import build_parser, main
from palpbayes.cli.options import options_from_args
from palpbayes.cli.report import plan_line
from palpbayes.paper import PAPER_MATERIALS, PAPER_TIPS
from palpbayes.sim import simulate

#: The fast options of every run here (the same on every run, so fits can be reused).
FAST = ["--workers", "1", "--engine", "exact", "--no-model-form", "--seed", "2"]


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    root = tmp_path_factory.mktemp("rerun")
    return simulate(
        root / "camp", seed=3, repetitions=2, gt_specimens=2, blocks=False,
        materials={"Foam": PAPER_MATERIALS["Pink"]},
        tips={"paraboloid": PAPER_TIPS["paraboloid"]})


@pytest.fixture(scope="module")
def fitted(campaign, tmp_path_factory):
    """The campaign fitted once: (results folder, console)."""
    out = tmp_path_factory.mktemp("rerun-results") / "res"
    code, console = _report(campaign, out)
    assert code == 0, console
    return out, console


def _report(campaign, out, *extra: str) -> tuple[int, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["report", str(campaign), "--out", str(out), "-o",
                     str(out.parent / f"{out.name}.pdf"), *FAST, *extra])
    return code, buf.getvalue()


def _pipeline(campaign, out, *extra: str) -> list[str]:
    """``run_pipeline`` with the options ``palpbayes report`` builds from FAST (+ ``extra``);
    the plan line it would print."""
    args = build_parser(("report",)).parse_args(["report", str(campaign), *FAST, *extra])
    lines: list[str] = []
    run_pipeline(campaign / "manifest.csv", out, options_from_args(args), workers=1,
                 progress=False, on_plan=lambda *plan: lines.append(plan_line(*plan)))
    return lines


def _copy(campaign, fitted, tmp_path):
    """A copy of the campaign and of its results folder (whose settings name the copy)."""
    camp = tmp_path / "camp"
    shutil.copytree(campaign, camp)
    out = tmp_path / "res"
    shutil.copytree(fitted[0], out)
    path = out / layout.SETTINGS
    settings = json.loads(path.read_text(encoding="utf-8"))
    settings["source"] = str((camp / "manifest.csv").resolve())
    path.write_text(json.dumps(settings), encoding="utf-8")
    return camp, out


def _mtimes(out) -> dict[str, int]:
    return {p.stem: p.stat().st_mtime_ns for p in (out / layout.POSTERIOR_DIR).glob("*.nc")}


def _e(out, trace_id: str, method: str = "bayes") -> float:
    s = pd.read_csv(out / layout.SUMMARY)
    return float(s.loc[(s.trace_id == trace_id) & (s.method == method), "E_pa"].iloc[0])


def test_first_run_says_it_fits_every_trace(fitted):
    _, console = fitted
    assert "fitting 2 traces" in console


def test_an_edited_trace_is_refitted_the_others_reused(campaign, fitted, tmp_path):
    camp, out = _copy(campaign, fitted, tmp_path)
    manifest = pd.read_csv(camp / "manifest.csv")
    edited, kept = manifest["trace_id"].iloc[0], manifest["trace_id"].iloc[1]
    before = {m: _e(out, edited, m) for m in ("bayes", "lsq")}
    kept_e = _e(out, kept)
    pooled_before = pd.read_csv(out / layout.POOLED)
    times = _mtimes(out)

    # the user edits the force column of one trace file by +4 %
    path = camp / manifest["file"].iloc[0]
    trace = pd.read_csv(path)
    trace["force_n"] *= 1.04
    trace.to_csv(path, index=False, float_format="%.10g")

    code, console = _report(camp, out)
    assert code == 0, console
    assert f"reusing 1 fits (inputs unchanged), refitting 1: {edited}" in console
    after = _mtimes(out)
    assert after[kept] == times[kept]  # reused: its posterior file untouched
    assert after[edited] != times[edited]
    # the refit sees the edit: E about 4 % higher, by both methods; the other trace as it was
    for m in ("bayes", "lsq"):
        assert _e(out, edited, m) / before[m] == pytest.approx(1.04, abs=0.01)
    assert _e(out, kept) == kept_e
    # everything downstream follows the refit
    pooled = pd.read_csv(out / layout.POOLED)
    assert not pooled.equals(pooled_before)

    # an unchanged re-run reuses every fit and writes no posterior
    times = _mtimes(out)
    code, console = _report(camp, out)
    assert code == 0 and "reusing 2 fits (inputs unchanged), refitting 0" in console
    assert _mtimes(out) == times


def test_an_edited_manifest_label_is_refitted(campaign, fitted, tmp_path):
    """A label the summary rows carry (the specimen) is an input too: the row must not keep the
    old one."""
    camp, out = _copy(campaign, fitted, tmp_path)
    manifest = pd.read_csv(camp / "manifest.csv", dtype=str, keep_default_na=False)
    edited = manifest["trace_id"].iloc[1]
    manifest.loc[1, "specimen"] = "Pink_renamed"
    manifest.to_csv(camp / "manifest.csv", index=False)
    plan = _pipeline(camp, out)
    s = pd.read_csv(out / layout.SUMMARY, dtype={"specimen": str})
    assert set(s.loc[s.trace_id == edited, "specimen"]) == {"Pink_renamed"}
    assert plan == [f"reusing 1 fits (inputs unchanged), refitting 1: {edited}"]


def test_other_options_or_another_version_refit_every_trace(campaign, fitted, tmp_path):
    camp, out = _copy(campaign, fitted, tmp_path)
    times = _mtimes(out)
    # argparse: the last --seed wins
    assert _pipeline(camp, out, "--seed", "7") == [
        "refitting all 2 traces (it was fitted with other options)"]
    assert all(_mtimes(out)[k] != t for k, t in times.items())

    settings = json.loads((out / layout.SETTINGS).read_text(encoding="utf-8"))
    settings["palpbayes_version"] = "0.0.1"
    (out / layout.SETTINGS).write_text(json.dumps(settings), encoding="utf-8")
    for record in (out / layout.PARTIAL_DIR).glob("*.json"):
        rec = json.loads(record.read_text(encoding="utf-8"))
        rec["palpbayes_version"] = "0.0.1"
        record.write_text(json.dumps(rec), encoding="utf-8")
    times = _mtimes(out)
    [line] = _pipeline(camp, out, "--seed", "7")
    assert line.startswith("refitting all 2 traces (it was fitted by palpbayes 0.0.1, this is")
    assert all(_mtimes(out)[k] != t for k, t in times.items())


def test_another_campaigns_folder_is_still_refused(campaign, fitted, tmp_path, capsys):
    other = tmp_path / "other"
    shutil.copytree(campaign, other)
    code, _ = _report(other, fitted[0])
    assert code == 2
    assert "holds results of another campaign" in capsys.readouterr().err
    # a folder of 'palpbayes fit MANIFEST' with reader options: refused, not refitted otherwise
    camp, out = _copy(campaign, fitted, tmp_path)
    settings = json.loads((out / layout.SETTINGS).read_text(encoding="utf-8"))
    settings["read_options"] = {"units": {"z": "mm"}}
    (out / layout.SETTINGS).write_text(json.dumps(settings), encoding="utf-8")
    times = _mtimes(out)
    code, _ = _report(camp, out)
    assert code == 2
    assert "read with column, unit or sign options" in capsys.readouterr().err
    assert _mtimes(out) == times


def test_plan_line_names_at_most_five_traces():
    ids = [f"t{i}" for i in range(7)]
    assert plan_line([], ids, None) == "fitting 7 traces"
    assert plan_line(["a"], ids, None) == ("reusing 1 fits (inputs unchanged), refitting 7: "
                                           "t0, t1, t2, t3, t4 and 2 more")
    assert plan_line([], ids, "it was fitted with other options") == (
        "refitting all 7 traces (it was fitted with other options)")
