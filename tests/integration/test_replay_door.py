"""``pb.replay`` (issue 57, one front door for every job): a recorded trace replayed from Python
in one call, with ``palpbayes replay``'s options by their Python names; ``.save`` writes the
command's files byte for byte, ``.summary()`` is its ``replay_summary.csv``, and both build
their options with one :class:`~palpbayes.api_replay.ReplayRequest`."""

from __future__ import annotations

import os

import numpy as np
import pytest
from matplotlib.figure import Figure

import palpbayes as pb
from palpbayes import outputs
from palpbayes.api_replay import Replay, ReplayRequest
from palpbayes.cli import build_parser, main
from palpbayes.cli.online_options import request_from_args
from palpbayes.errors import InputError
from palpbayes.io.atomic import write_csv_atomic

E_TRUE = 1.25e5
PARABOLOID = pb.paper.PAPER_TIPS["paraboloid"]  # R = 11.7 mm
FILES = (outputs.REPLAY_HISTORY, outputs.REPLAY_SUMMARY, outputs.REPLAY_FIGURE)


@pytest.fixture(scope="module")
def press(tmp_path_factory):
    """A paraboloid 3 mm into a 125 kPa block, written as a trace CSV (as docs/api.md does)."""
    trace = pb.simulate_trace(E_TRUE, PARABOLOID, thickness=0.03, force_offset=0.05, rng=17,
                              base=None, trace_id="para")
    return pb.write_trace(trace, tmp_path_factory.mktemp("trace") / "para.csv")


@pytest.fixture(scope="module")
def replayed(press):
    """``pb.replay`` of the press, stopping at a ±5 % full interval (3 lines from the import)."""
    return pb.replay(press, tip="paraboloid", radius=0.0117, target="5%")


def _same_files(cli_args, source, kwargs, tmp_path, capsys, truth=None):
    """Run ``palpbayes replay SOURCE CLI_ARGS --out A`` and ``pb.replay(SOURCE, **KWARGS)
    .save(B)``; assert the files are the same bytes; the Python result."""
    a, b = tmp_path / "cli", tmp_path / "py"
    argv = ["replay", str(source), *cli_args, "--out", str(a)]
    if truth is not None:
        argv += ["--truth", str(truth)]
    assert main(argv) == 0, capsys.readouterr().err
    capsys.readouterr()
    res = pb.replay(source, **kwargs)
    assert isinstance(res, Replay)
    assert res.save(b, truth=truth) == b
    for name in FILES:
        assert (b / name).read_bytes() == (a / name).read_bytes(), name
    # .summary() is the file: written with the command line's writer, the same bytes
    write_csv_atomic(res.summary(), tmp_path / "ours.csv")
    assert (tmp_path / "ours.csv").read_bytes() == (a / outputs.REPLAY_SUMMARY).read_bytes()
    assert sorted(os.listdir(b)) == sorted(FILES)  # no staging folder left behind
    return res


@pytest.mark.parametrize("cli_args, kwargs", [
    (["--target", "5%"], {"target": "5%"}),
    (["--max-depth", "5e-4", "--chunk", "50", "--noise", "ar1", "--target-on", "stat",
      "--nu", "0.45", "--noise-pp", "0.02"],
     {"max_depth": 5e-4, "chunk": 50, "noise": "ar1", "target_on": "stat", "nu": 0.45,
      "noise_pp": 0.02}),
], ids=["target", "max-depth-ar1"])
def test_the_door_writes_the_command_lines_files(press, tmp_path, capsys, cli_args, kwargs):
    res = _same_files(["--tip", "paraboloid", "--radius", "0.0117", *cli_args], press,
                      {"tip": "paraboloid", "radius": 0.0117, **kwargs}, tmp_path, capsys,
                      truth=E_TRUE)
    assert res.at_stop is not None and res.trace_id == "para"
    table = res.summary()
    assert table.shape[0] == 1 and list(table.columns) == list(res.row)


@pytest.mark.parametrize("name", ["afm-curves/force-save-example.csv",
                                  "afm-files/fmt-jpk-fd_spot3-0192.jpk-force"])
def test_the_door_replays_real_curves_as_the_command_line(shared_data, tmp_path, capsys, name):
    """Two real AFM approaches (../shared/data; skipped without it): a curve exported as CSV
    and a JPK file (the door reads its approach, as the command line does)."""
    source = shared_data(name)
    res = _same_files(["--tip", "paraboloid", "--radius", "10e-6", "--nu", "0.5", "--target",
                       "10%"], source,
                      {"tip": "paraboloid", "radius": 10e-6, "nu": 0.5, "target": 0.1},
                      tmp_path, capsys)
    assert res.row["nu"] == 0.5 and np.isfinite(res.row["E_final_pa"])


def test_the_command_line_and_the_door_build_one_request():
    """Defaults and checks cannot drift: the parser's defaults make the request's."""
    args = build_parser().parse_args(["replay", "press.csv", "--target", "5%"])
    assert request_from_args(args) == ReplayRequest(target="5%") == ReplayRequest(target=0.05)
    req = ReplayRequest(max_depth=1e-3)
    assert (req.chunk, req.noise, req.target_on, req.seed) == (100, "gaussian", "full", 0)
    assert req.rule == pb.StoppingRule(max_depth=1e-3, target_on="full")


@pytest.mark.parametrize("kwargs, message", [
    ({}, "give a stopping rule"),
    ({"target": "150%"}, r"target '150%' must lie between 0 and 100 %"),
    ({"target": "five"}, "target 'five' is not a fraction"),
    ({"target": 0.05, "tagret": 0.05}, "unknown option.*tagret"),
    ({"max_force": -1.0}, "max_force = -1.0 must be a positive number"),
    ({"max_depth": "deep"}, "max_depth = 'deep'"),
    ({"target": 0.05, "target_on": "both"}, "target_on = 'both'"),
    ({"target": 0.05, "min_contact": 0}, "min_contact = 0"),
    ({"target": 0.05, "chunk": 0}, "chunk = 0 samples"),
    ({"target": 0.05, "chunk": 2.5}, "chunk = 2.5 must be a whole number"),
    ({"target": 0.05, "noise": "student"}, "noise.*'student'"),
    ({"target": 0.05, "noise_pp": -0.1}, "noise_pp = -0.1"),
    ({"target": 0.05, "nu": 0.7}, "0.7"),
    ({"target": 0.05, "thickness": "unknown"}, "needs a known thickness"),
    ({"target": 0.05, "thickness": -1}, "--thickness -1 must be a positive"),
    ({"target": 0.05, "bonding": "glued"}, "bonding 'glued'"),
    ({"target": 0.05, "seed": -1}, "seed -1"),
])
def test_a_bad_option_is_named_before_the_file_is_read(tmp_path, kwargs, message):
    """Every option is checked before the file is read (this one does not exist)."""
    with pytest.raises(InputError, match=message):
        pb.replay(tmp_path / "none.csv", tip="paraboloid", radius=0.0117, **kwargs)


def test_a_file_needs_the_tip_and_a_layer_its_base(press):
    with pytest.raises(InputError, match="needs the tip"):
        pb.replay(press, target=0.05)
    with pytest.raises(InputError, match="--bonding bonded"):
        pb.replay(press, tip="paraboloid", radius=0.0117, target=0.05, thickness=0.03)
    with pytest.raises(InputError, match="give --thickness M too"):
        pb.replay(press, tip="paraboloid", radius=0.0117, target=0.05, bonding="free")
    with pytest.raises(InputError, match="replay takes a path"):
        pb.replay(42, target=0.05)


def test_a_trace_is_replayed_with_its_own_tip_and_thickness():
    """An IndentationTrace keeps its tip and its thickness (a thickness is never dropped: the
    base must be given)."""
    trace = pb.simulate_trace(60e3, pb.Tip("sphere", radius=0.01), nu=0.45, z_surf=0.022,
                              thickness=0.02, depth=2e-3, approach=1e-3, rate=250.0,
                              force_offset=0.21, base="bonded", rng=7, trace_id="layer")
    with pytest.raises(InputError, match="--bonding bonded"):
        pb.replay(trace, nu=0.45, max_depth=1e-3)
    res = pb.replay(trace, nu=0.45, max_depth=1e-3, bonding="bonded")
    row = res.row
    assert (row["thickness_m"], row["bonding"], row["reason"]) == (0.02, "bonded", "max depth")
    assert row["E_total_final_lo_pa"] <= 60e3 <= row["E_total_final_hi_pa"]


def _at(values, v: float) -> bool:
    """A straight line's two ends (axvline's x, axhline's y) at ``v``."""
    values = np.asarray(values, dtype=float)
    return values.shape == (2,) and bool(np.allclose(values, v))


def test_the_figure_shows_the_stop_and_the_target(replayed):
    fig = replayed.plot(truth=E_TRUE)
    assert isinstance(fig, Figure) and fig._suptitle.get_text() == "para"
    top, bottom = fig.axes[:2]
    stop_mm = replayed.at_stop.depth * 1e3
    for ax in (top, bottom):  # the vertical line at the stop's depth, on both panels
        assert any(_at(line.get_xdata(), stop_mm) for line in ax.get_lines())
    assert [t.get_text() for t in top.texts] == ["stop"]
    # the target (±5 %) on the half-width panel, the truth (125 kPa) on the modulus panel
    assert any(_at(line.get_ydata(), 5.0) for line in bottom.get_lines())
    assert any(_at(line.get_ydata(), 125.0) for line in top.get_lines())


def test_the_result_says_where_it_stopped(replayed):
    text = repr(replayed)
    assert text.startswith("Replay('para': stopped (target precision) at ")
    assert "whole trace" in text and "kPa" in text and len(text) < 250
    row = replayed.row
    assert row["stopped"] and row["reason"] == "target precision"
    assert row["depth_saved_pct"] > 0


def test_save_is_all_or_nothing(replayed, tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / outputs.REPLAY_HISTORY).write_text("old\n")
    (out / "notes.txt").write_text("mine\n")

    def broken(self, truth=None):
        raise RuntimeError("no figure")

    monkeypatch.setattr(Replay, "plot", broken)
    with pytest.raises(RuntimeError, match="no figure"):
        replayed.save(out)
    # the old file as it was, no half of the new ones, no staging folder
    assert sorted(os.listdir(out)) == sorted([outputs.REPLAY_HISTORY, "notes.txt"])
    assert (out / outputs.REPLAY_HISTORY).read_text() == "old\n"
    monkeypatch.undo()
    replayed.save(out)
    assert sorted(os.listdir(out)) == sorted([*FILES, "notes.txt"])
    with pytest.raises(InputError, match="cannot create the folder"):
        replayed.save(out / "notes.txt")
