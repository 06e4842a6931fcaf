"""Search-state folders, a map folder read as a state, and ``palpbayes next``."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from palpbayes.active.files import PRESSES_FILE, SEARCH_FILE, append_press, init_state, read_state
from palpbayes.cli import main
from palpbayes.cli.next import EXIT_DECIDED, EXIT_GO_ON
from palpbayes.errors import DataFileError, OutputExistsError
from palpbayes.inclusion import Inclusion
from palpbayes.sim.phantom import MapPhantom

FOOT = (0.0, 0.042, 0.0, 0.042)
INIT = ["--init", "--footprint", "0,0.042,0,0.042", "--thickness", "0.02", "--tip",
        "paraboloid", "--radius", "0.0117", "--depth", "0.002"]


def _fill(folder, n, lump=True, seed=0):
    """Append the next n presses of an 11 x 11 raster, read off a phantom's smooth field
    (+3 % heterogeneity)."""
    inc = Inclusion(x=0.014, y=0.027, depth=5.5e-3, radius=5e-3, ratio=10.0) if lump else None
    ph = MapPhantom(inclusion=inc)
    rng = np.random.default_rng(seed)
    st = read_state(folder)
    m = 11
    g = (np.arange(m) + 0.5) / m * 0.042
    grid = list(zip(*(a.ravel() for a in np.meshgrid(g, g)), strict=True))
    for x, y in grid[st.n:st.n + n]:
        mean = float(np.log(ph.apparent_modulus(x, y))) + 0.03 * rng.standard_normal()
        st = append_press(folder, st, x, y, mean, 0.0015)
    return st


def test_init_read_append_round_trip(tmp_path):
    d = tmp_path / "s"
    st = init_state(d, footprint=FOOT, contact_radius=0.0048, thickness=0.02,
                    keep_out=[(0.01, 0.01, 0.003)], min_spacing_m=0.002)
    assert st.n == 0 and (d / SEARCH_FILE).is_file() and (d / PRESSES_FILE).is_file()
    back = read_state(d)
    assert back.footprint == FOOT and back.keep_out == ((0.01, 0.01, 0.003),)
    assert back.min_spacing == 0.002 and back.contact_radius == 0.0048
    st = append_press(d, back, 0.02, 0.02, 10.8, 0.01, p_lump=0.4)
    again = read_state(d)
    assert again.n == 1 and again.presses["p_lump"].iloc[0] == 0.4
    with pytest.raises(OutputExistsError, match="exists"):
        init_state(d, footprint=FOOT, contact_radius=0.0048, thickness=0.02)


def test_a_map_folder_is_read_as_a_state(tmp_path):
    pts = pd.DataFrame({"trace_id": ["a", "b", "c"], "x_m": [0.0, 0.003, 0.006],
                        "y_m": [0.0, 0.0, 0.0], "logE_mean": [10.8, np.nan, 10.9],
                        "logE_sd": [0.01, np.nan, 0.02]})
    pts.to_csv(tmp_path / "points.csv", index=False)
    settings = {"contact_radius_m": 0.0048, "thickness_m": 0.02,
                "lattice": {"x0_m": 0.0, "y0_m": 0.0, "step_m": 0.003, "nx": 3, "ny": 2}}
    (tmp_path / "settings.json").write_text(json.dumps(settings))
    st = read_state(tmp_path)
    assert st.n == 2  # the point without a fit is not a press
    assert st.footprint == (0.0, 0.006, 0.0, 0.003)


@pytest.mark.parametrize("setup, match", [
    (lambda d: None, "holds no search state"),
    (lambda d: (d / SEARCH_FILE).write_text("{not json"), "not readable JSON"),
    (lambda d: (d / SEARCH_FILE).write_text('{"footprint_m": [0, 1]}'), "not a search state"),
])
def test_bad_folders_name_the_file(tmp_path, setup, match):
    setup(tmp_path)
    with pytest.raises(DataFileError, match=match) as err:
        read_state(tmp_path)
    assert str(tmp_path) in str(err.value)


def test_a_bad_press_row_is_named(tmp_path):
    init_state(tmp_path, footprint=FOOT, contact_radius=0.0048, thickness=0.02)
    (tmp_path / PRESSES_FILE).write_text("x_m,y_m,logE_mean,logE_sd\n0.01,0.01,10.8,0.01\n"
                                         "0.02,0.02,abc,0.01\n")
    with pytest.raises(DataFileError, match=r"row 3, column logE_mean: 'abc'"):
        read_state(tmp_path)
    (tmp_path / PRESSES_FILE).write_text("x_m,y_m,logE_mean,logE_sd\n0.01,0.01,10.8,0\n")
    with pytest.raises(DataFileError, match=r"row 2, column logE_sd: .* > 0"):
        read_state(tmp_path)
    (tmp_path / PRESSES_FILE).write_text("x_m,y_m,logE_mean\n0.01,0.01,10.8\n")
    with pytest.raises(DataFileError, match="no column logE_sd"):
        read_state(tmp_path)


def test_cli_init_then_next_then_decide(tmp_path, capsys):
    d = str(tmp_path / "s")
    assert main(["next", d, *INIT]) == 0
    capsys.readouterr()
    assert main(["next", d, "--json", "--plot", str(tmp_path / "none.png")]) == EXIT_GO_ON
    out = capsys.readouterr()
    first = json.loads(out.out)
    assert "no press yet" in out.err and not (tmp_path / "none.png").exists()
    assert first["event"] == "next" and first["presses"][0]["x_m"] == pytest.approx(0.022)
    _fill(d, 16)
    assert main(["next", d, "--plot", str(tmp_path / "s.png")]) == EXIT_GO_ON
    assert "next press 1: x" in capsys.readouterr().out
    assert (tmp_path / "s.png").stat().st_size > 20000
    _fill(d, 121 - 16, seed=1)
    code = main(["next", d, "--centre-radius", "0.003"])
    out = capsys.readouterr().out
    assert code == EXIT_DECIDED and "DECIDED: a lump" in out, out
    assert main(["next", d, "--json", "--centre-radius", "1e-5", "-k", "2",
                 "--keep-out", "0.014,0.027,0.004"]) == EXIT_GO_ON
    ans = json.loads(capsys.readouterr().out)
    assert len(ans["presses"]) == 2 and 0.99 < ans["p_lump"] <= 1
    for p in ans["presses"]:
        assert np.hypot(p["x_m"] - 0.014, p["y_m"] - 0.027) > 0.004


def test_the_python_door_gives_the_commands_table(tmp_path, capsys):
    """``pb.next_presses(DIR).table()`` is the file ``palpbayes next DIR --out`` writes, byte
    for byte, going on (two presses) and decided (one row, no press)."""
    import palpbayes as pb
    from palpbayes.active import SearchStopRule

    d = str(tmp_path / "s")
    assert main(["next", d, *INIT]) == 0
    _fill(d, 16)
    cases = (("going on", 2, [], SearchStopRule(), EXIT_GO_ON),
             ("decided", 1, ["--centre-radius", "0.003"], SearchStopRule(centre_radius=3e-3),
              EXIT_DECIDED))
    for what, k, flags, rule, code in cases:
        if what == "decided":
            _fill(d, 121 - 16, seed=1)
        out = tmp_path / f"{what}.csv"
        assert main(["next", d, "-k", str(k), "--out", str(out), *flags]) == code
        mine = tmp_path / f"{what}-python.csv"
        pb.next_presses(d, k, rule=rule).table().to_csv(mine, index=False)
        assert mine.read_bytes() == out.read_bytes(), what
        back = pd.read_csv(out)
        if what == "going on":
            assert len(back) == 2 and set(back["event"]) == {"next"}
            assert back["n"].tolist() == [16, 16] and back["order"].tolist() == [1, 2]
        else:
            assert len(back) == 1 and back["event"][0] == "done"
            assert back["decision"][0] == "lump" and back["n"][0] == 121
            assert back["x_m"].isna().all() and back["x_m_centre"][0] == pytest.approx(0.014,
                                                                                         abs=2e-3)
    capsys.readouterr()


@pytest.mark.parametrize("args, match", [
    (["--init", "--thickness", "0.02"], "--footprint"),
    (["--init", "--footprint", "0,1,0", "--thickness", "0.02", "--tip", "paraboloid",
      "--radius", "0.01"], "--footprint"),
    (["--keep-out", "1,2"], "--keep-out"),
    (["--init", "--footprint", "0,-0.01,0,0.01", "--thickness", "0.02", "--tip", "paraboloid",
      "--radius", "0.01"], "--footprint"),
    (["--init", "--footprint", "0,0.04,0,0.04", "--thickness", "0.002", "--tip",
      "paraboloid", "--radius", "0.01", "--depth", "0.0002"], "too thin"),
])
def test_cli_errors_name_the_option(tmp_path, capsys, args, match):
    d = str(tmp_path / "s")
    if "--init" not in args:
        assert main(["next", d, *INIT]) == 0
    assert main(["next", d, *args]) == 2
    assert match in capsys.readouterr().err
    if "--init" in args:  # nothing half-written
        assert not (tmp_path / "s").exists()


def test_cli_on_a_folder_without_a_state(tmp_path, capsys):
    assert main(["next", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert str(tmp_path) in err and "--init" in err
