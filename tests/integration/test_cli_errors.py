"""Bad-input matrix: every case exits 2, prints one clear line, writes nothing."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.io.trace_csv import write_trace
from palpbayes.sim import simulate_trace

TIP = ["--tip", "sphere", "--radius", "0.01"]


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    d = tmp_path_factory.mktemp("good")
    tr = simulate_trace(136e3, Tip("sphere", radius=0.01), thickness=0.02, rng=1, base=None)
    return tr, write_trace(tr, d / "good.csv")


def _frame(tr):
    return pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": tr.force})


def _run(tmp_path, capsys, args):
    out = tmp_path / "results"
    rc = main(["fit", *args, "--out", str(out), "--method", "lsq"])
    err = capsys.readouterr().err.strip()
    return rc, err, out


def _bad_csv(tmp_path, tr, case):
    df = _frame(tr)
    p = tmp_path / f"{case}.csv"
    if case == "misspelled":
        df = df.rename(columns={"force_n": "forse_n"})
    elif case == "missing":
        df = df.drop(columns="z_m")
    elif case == "3m":
        df["z_m"] = df["z_m"] * 1000  # mm values in a metre column
    elif case == "5kN":
        df["force_n"] = df["force_n"] * 5000 / df["force_n"].max()
    elif case == "nan":
        df.loc[100, "force_n"] = np.nan
    elif case == "inf":
        df.loc[100, "z_m"] = np.inf
    elif case == "text":
        df = df.astype(object)
        df.loc[100, "force_n"] = "1,2"
    elif case == "duplicate":
        df.loc[101, "time_s"] = df.loc[100, "time_s"]
    elif case == "decreasing":
        df.loc[101, "time_s"] = df.loc[100, "time_s"] - 1e-3
    elif case == "nocontact":
        df = df[df["z_m"] > tr.metadata["z_surf_true"] + 1e-4]
    elif case == "flipped":
        df["force_n"] = -df["force_n"]
    elif case in ("cm", "cm_thick"):
        df["z_m"] = df["z_m"] * 100  # cm values in a metre column (span 0.3 "m" passes)
    if case == "empty":
        p.write_text("")
    elif case == "header":
        p.write_text("time_s,z_m,force_n\n")
    elif case == "semicolon_dc":
        df.to_csv(p, sep=";", decimal=",", index=False)
    elif case == "comma_dc":
        p.write_text("time_s,z_m,force_n\n" + "".join(
            f"{t:.5f},{z:.7f},{f:.4f}\n".replace(".", ",")
            for t, z, f in zip(df["time_s"], df["z_m"], df["force_n"], strict=True)))
    else:
        df.to_csv(p, index=False)
    return p


CASES = {
    "misspelled": "missing column 'force_n'",
    "missing": "missing column 'z_m'",
    "3m": "--z-unit mm",
    "5kN": "--force-unit mN",
    "nan": "'force_n' is empty \\(NaN\\) at data row 101",
    "inf": "'z_m' is infinite at data row 101",
    "text": "non-numeric value '1,2'",
    "empty": "file is empty",
    "header": "no data rows",
    "duplicate": "time repeats at data row 102",
    "decreasing": "time decreases at data row 102",
    "nocontact": "never leaves",
    "flipped": "--force-sign -1",
    "semicolon_dc": "non-numeric value '0,00125' at data row 1: the file uses decimal commas",
    "comma_dc": "3 more field\\(s\\) than the header \\(3 columns\\); decimal commas",
    "cm": "indentation depth 176.8 mm .*exceeds the tip radius 10 mm.*--z-unit",
    "cm_thick": "indentation depth 176.8 mm .*exceeds the specimen thickness 20 mm.*--z-unit",
}
#: Extra command-line arguments of some cases.
CASE_ARGS = {"cm_thick": ["--thickness", "0.02"]}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_trace_files(tmp_path, capsys, good, case):
    path = _bad_csv(tmp_path, good[0], case)
    rc, err, out = _run(tmp_path, capsys, [str(path), *TIP, *CASE_ARGS.get(case, [])])
    assert rc == 2
    assert len(err.splitlines()) == 1, err
    assert str(path) in err
    assert re.search(CASES[case], err), err
    assert not out.exists()


@pytest.mark.parametrize("args, match", [
    (["--tip", "sphere"], "radius \\[m\\] is missing \\(give --radius"),
    (["--tip", "sphere", "--radius", "-0.01"], "must be a positive finite number"),
    ([], "needs --tip"),
    (TIP + ["--nu", "0.6"], "Poisson ratio nu = 0.6 is outside \\[0, 0.5\\]"),
    (TIP + ["--nu", "-0.1"], "outside \\[0, 0.5\\]"),
    (TIP + ["--nu-range", "0.2", "0.6"], "outside \\[0, 0.5\\]"),
    (["--tip", "cone", "--half-angle", "95"],
     "cone half-angle 95.0 deg must lie strictly between 0 and 90 deg"),
    (["--tip", "cone", "--half-angle", "0"], "half-angle 0.0 deg must lie strictly between"),
])
def test_bad_options(tmp_path, capsys, good, args, match):
    rc, err, out = _run(tmp_path, capsys, [str(good[1]), *args])
    assert rc == 2 and len(err.splitlines()) == 1 and re.search(match, err), err
    assert not out.exists()


#: Geometry the pre-check must refuse before anything is written (the trace file is named).
GEOMETRY = {
    "radius_mm": (["--tip", "sphere", "--radius", "10"],
                  "tip radius 10 m is implausibly large.*--radius is in metres.*did you mean "
                  "0.010\\?"),
    "flat_radius_mm": (["--tip", "flat", "--radius", "10"], "did you mean 0.010\\?"),
    "thinner_than_depth": (TIP + ["--thickness", "0.001"],
                           "indentation depth 1.768 mm .*exceeds the specimen thickness 1 mm"),
    "deeper_than_radius": (["--tip", "paraboloid", "--radius", "0.001"],
                           "exceeds the tip radius 1 mm, outside the Hertz law's validity"),
}


@pytest.mark.parametrize("case", list(GEOMETRY))
def test_bad_geometry_is_refused_before_writing(tmp_path, capsys, good, case):
    args, match = GEOMETRY[case]
    rc, err, out = _run(tmp_path, capsys, [str(good[1]), *args])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert str(good[1]) in err and re.search(match, err), err
    assert not out.exists()


#: Layer options that must be refused before anything is read: (options, expected message).
LAYER_OPTIONS = {
    "thickness_word": (["--thickness", "thick"], "neither a thickness in metres nor 'unknown'"),
    "thickness_zero": (["--thickness", "0"], "must be a positive thickness in metres"),
    "half_space_and_unknown": (["--half-space", "--thickness", "unknown"],
                               "contradict each other"),
    "range_without_unknown": (["--thickness", "0.02", "--thickness-range", "0.001", "0.1"],
                              "prior of an unknown thickness: give it with --thickness unknown"),
    "range_reversed": (["--thickness", "unknown", "--thickness-range", "0.1", "0.01"],
                       "0 < LO < HI"),
}


@pytest.mark.parametrize("case", list(LAYER_OPTIONS))
def test_bad_layer_options_are_one_line(tmp_path, capsys, good, case):
    args, match = LAYER_OPTIONS[case]
    rc, err, out = _run(tmp_path, capsys, [str(good[1]), *TIP, *args])
    assert rc == 2 and len(err.splitlines()) == 1 and re.search(match, err), err
    assert not out.exists()


def test_failed_precheck_keeps_previous_results_with_force(tmp_path, capsys, good):
    """Issue: a bad model that escaped the pre-check deleted the old results under --force and
    left settings.json + traces.csv of the failed run."""
    rc, _, out = _run(tmp_path, capsys, [str(good[1]), *TIP])
    assert rc == 0
    before = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert Path("summary.csv") in before
    rc, err, _ = _run(tmp_path, capsys, [str(good[1]), *GEOMETRY["thinner_than_depth"][0],
                                         "--force"])
    assert rc == 2 and len(err.splitlines()) == 1 and "specimen thickness" in err, err
    after = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before


def _manifest(tmp_path, tr, rows, name="manifest.csv", frame=None):
    camp = tmp_path / "camp"
    camp.mkdir(exist_ok=True)
    (frame if frame is not None else _frame(tr)).to_csv(camp / "a.csv", index=False)
    base = {"trace_id": "a", "file": "a.csv", "material": "W", "tip": "sphere",
            "radius_m": "0.01", "thickness_m": "0.02", "repetition": "1"}
    pd.DataFrame([{**base, **r} for r in rows]).to_csv(camp / name, index=False)
    return camp / name


#: Manifest cells that must be refused: (changed cells, expected message).
MANIFEST_CASES = {
    "radius_text": ({"radius_m": "abc"}, "row 1 \\(trace 'a'\\): column 'radius_m' holds "
                    "'abc', which is not a number \\(write a plain number in metres"),
    "repetition_text": ({"repetition": "first"},
                        "column 'repetition' holds 'first', which is not a number"),
    "repetition_fraction": ({"repetition": "1.5"}, "column 'repetition' is 1.5, not a whole"),
    "thickness_unit": ({"thickness_m": "2cm"}, "column 'thickness_m' holds '2cm'"),
    "thickness_negative": ({"thickness_m": "-0.02"}, "column 'thickness_m' is -0.02, which "
                           "must be positive"),
    "empty_trace_id": ({"trace_id": ""}, "row 1: column 'trace_id' is empty"),
    "empty_material": ({"material": ""}, "column 'material' is empty"),
    "cone_angle": ({"tip": "cone", "radius_m": "", "half_angle_deg": "95"},
                   "cone half-angle 95.0 deg must lie strictly between 0 and 90 deg"),
    "radius_mm": ({"radius_m": "10"}, "tip radius 10 m is implausibly large.*did you mean "
                  "0.010\\?"),
}


@pytest.mark.parametrize("case", list(MANIFEST_CASES))
def test_bad_manifest_cells(tmp_path, capsys, good, case):
    cells, match = MANIFEST_CASES[case]
    m = _manifest(tmp_path, good[0], [cells])
    rc, err, out = _run(tmp_path, capsys, [str(m)])
    assert rc == 2 and len(err.splitlines()) == 1, err
    named = str(m) if case != "radius_mm" else str(m.parent / "a.csv")
    assert named in err and re.search(match, err), err
    assert not out.exists()


def test_manifest_traces_get_the_sign_and_unit_options(tmp_path, capsys, good):
    tr = good[0]
    raw = pd.DataFrame({"time_s": tr.time, "z_mm": tr.z * 1e3, "force_n": -tr.force})
    m = _manifest(tmp_path, tr, [{}], frame=raw)
    rc, err, out = _run(tmp_path, capsys, [str(m)])
    assert rc == 2 and len(err.splitlines()) == 1, err  # the advice names the option ...
    assert str(m.parent / "a.csv") in err and "--force-sign -1" in err, err
    assert not out.exists()
    rc, err, out = _run(tmp_path, capsys, [str(m), "--force-sign", "-1"])  # ... which works
    assert rc == 0, err
    summary = pd.read_csv(out / "summary.csv")
    assert summary["E_pa"].iloc[0] == pytest.approx(136e3, rel=0.01)
    # the column and unit options reach the manifest's traces too
    raw.rename(columns={"z_mm": "height"}).to_csv(m.parent / "a.csv", index=False)
    rc, err, out2 = _run(tmp_path / "x", capsys, [str(m), "--force-sign", "-1",
                                                 "--z-column", "height", "--z-unit", "mm"])
    assert rc == 0, err
    assert pd.read_csv(out2 / "summary.csv")["E_pa"].iloc[0] == summary["E_pa"].iloc[0]


def test_output_below_a_file(tmp_path, capsys, good):
    blocker = tmp_path / "results"
    blocker.write_text("not a folder")
    rc = main(["fit", str(good[1]), *TIP, "--out", str(blocker / "sub"), "--method", "lsq"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"cannot create output folder {blocker / 'sub'}: {blocker} is a file" in err
    assert blocker.read_text() == "not a folder"


def test_folder_as_input(tmp_path, capsys, good):
    folder = tmp_path / "camp"
    folder.mkdir()
    rc, err, out = _run(tmp_path, capsys, [str(folder), *TIP])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"{folder}: is a folder, not a file" in err and "not found" not in err
    m = _manifest(tmp_path, good[0], [{}])
    rc, err, out = _run(tmp_path, capsys, [str(m.parent)])
    assert rc == 2 and f"did you mean {m}?" in err, err
    assert not out.exists()


def test_semicolon_separated_trace_is_read(tmp_path, capsys, good):
    p = tmp_path / "semi.csv"
    _frame(good[0]).to_csv(p, sep=";", index=False, float_format="%.17g")
    rc, err, out = _run(tmp_path, capsys, [str(p), *TIP])
    assert rc == 0, err
    assert pd.read_csv(out / "summary.csv")["E_pa"].iloc[0] == pytest.approx(136e3, rel=0.01)


def test_manifest_with_missing_file(tmp_path, capsys, good):
    m = tmp_path / "manifest.csv"
    pd.DataFrame([{"trace_id": "a", "file": "nowhere.csv", "material": "W", "tip": "sphere",
                   "radius_m": 0.01}]).to_csv(m, index=False)
    rc, err, out = _run(tmp_path, capsys, [str(m)])
    assert rc == 2 and "points to missing file" in err and str(m) in err
    assert not out.exists()


def test_existing_results_need_force(tmp_path, capsys, good):
    rc, err, out = _run(tmp_path, capsys, [str(good[1]), *TIP])
    assert rc == 0 and (out / "summary.csv").is_file()
    before = (out / "summary.csv").read_bytes()
    rc, err, _ = _run(tmp_path, capsys, [str(good[1]), *TIP])
    assert rc == 2 and "--force" in err
    assert (out / "summary.csv").read_bytes() == before


def test_real_process_exit_status(tmp_path, good):
    bad = _bad_csv(tmp_path, good[0], "flipped")
    proc = subprocess.run([sys.executable, "-m", "palpbayes", "fit", str(bad), *TIP, "--out",
                           str(tmp_path / "r")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "--force-sign -1" in proc.stderr
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_million_row_trace(tmp_path, capsys):
    """A 10^6-row trace (3 mm at ~208 kHz) fits end to end with both methods.  Time and memory
    are measured by benchmarks/bench_long_trace.py (10 s, 357 MB peak RSS on 2 cores)."""
    tr = simulate_trace(111e3, Tip("paraboloid", radius=0.0117), thickness=0.03,
                        rate=208_333.0, rng=1, base=None)
    assert tr.n_points > 999_000
    path = write_trace(tr, tmp_path / "big.csv")
    out = tmp_path / "res"
    rc = main(["fit", str(path), "--tip", "paraboloid", "--radius", "0.0117", "--out", str(out),
               "--method", "both"])
    assert rc == 0, capsys.readouterr().err
    summary = pd.read_csv(out / "summary.csv")
    assert set(summary["method"]) == {"lsq", "bayes"}
    assert np.all(np.abs(summary["E_pa"] / 111e3 - 1) < 0.01)


@pytest.mark.parametrize("payload", [
    {"time_s": [0.0, 0.1, 0.2], "z_m": [0.1, 0.099, 0.098], "force_n": [0.0, 0.5, 1.0]},
    [{"time_s": 0.1 * i, "z_m": 0.1 - 1e-3 * i, "force_n": 0.5 * i} for i in range(4)],
])
def test_a_json_file_is_named_json_not_decimal_commas(tmp_path, capsys, payload):
    """Issue 46: a JSON recording given as a trace got a hint about decimal commas."""
    import json

    path = tmp_path / "press.json"
    path.write_text(json.dumps(payload, indent=2))
    rc, err, _ = _run(tmp_path, capsys, [str(path), *TIP])
    assert rc == 2 and "press.json" in err
    assert "is JSON, not a delimited table" in err and "to_csv" in err
    assert "decimal comma" not in err
    # an INI-like section header is not taken for JSON
    ini = tmp_path / "section.csv"
    ini.write_text("[Data]\ntime_s,z_m,force_n\n")
    rc, err, _ = _run(tmp_path, capsys, [str(ini), *TIP])
    assert "JSON" not in err


def test_fit_help_states_the_budget_defaults(capsys):
    """Issue 46: the budget's defaults (nu ± 0.05, compliance 2 µm/N) were not in --help."""
    from palpbayes.bayes.budget import BudgetSpec

    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    b = BudgetSpec()
    assert f"nu ± {b.nu_half_width:g}" in text
    assert f"{b.compliance_max * 1e6:g} µm/N" in text
    assert "tip radius ± 1%" in text and "a known thickness ± 2%" in text
