"""A trace is prepared once per fit (issue 45): ``palpbayes fit`` checks a trace before it
writes anything and then fits it; both use one :func:`palpbayes.fitdata.prepare`.  The
paper's Hertz column's tared data come from it (:func:`palpbayes.fitdata.tared`), equal to a
second prepare with ``tare=True``."""

from __future__ import annotations

import cProfile
import dataclasses
import pstats
from pathlib import Path

import numpy as np
import pytest

from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.fitdata import ModelSpec, prepare, tared
from palpbayes.io.trace_csv import read_trace

EXAMPLE = Path(__file__).resolve().parents[2] / "data" / "example-campaign" / "traces"


def _calls(stats: pstats.Stats, module: str, name: str) -> int:
    return sum(v[1] for k, v in stats.stats.items()
               if k[2] == name and k[0].replace("\\", "/").endswith(module))


@pytest.mark.parametrize("method, tare", [("lsq", False), ("both", False), ("lsq", True)])
def test_one_fit_prepares_the_trace_once(tmp_path, method, tare):
    args = ["fit", str(EXAMPLE / "Grey_sphere_r01.csv"), "--tip", "sphere", "--radius", "0.01",
            "--nu", "0.3", "--method", method, "--engine", "exact", "--no-model-form",
            "--out", str(tmp_path / "out"), *(["--tare"] if tare else [])]
    prof = cProfile.Profile()
    prof.enable()
    try:
        assert main(args) in (0, None)
    finally:
        prof.disable()
    stats = pstats.Stats(prof)
    assert _calls(stats, "palpbayes/fitdata.py", "prepare") == 1
    assert _calls(stats, "palpbayes/campaign/fitjob.py", "check_fittable") == 1
    # the paper's least squares: the row, and the Hertz ratio's fits on the tared force (the
    # exact law's is the row's when the force is tared already)
    assert _calls(stats, "palpbayes/lsq.py", "fit_lsq_data") == (2 if tare else 3)
    assert (tmp_path / "out" / "summary.csv").is_file()


def _same(a, b, where: str) -> None:
    """Field by field, arrays element by element (the traces' and baselines' too)."""
    if isinstance(b, np.ndarray):
        np.testing.assert_array_equal(a, b, err_msg=where)
    elif dataclasses.is_dataclass(b) and not isinstance(b, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(b):
            _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(b, dict):
        assert a.keys() == b.keys(), where
        for k in b:
            _same(a[k], b[k], f"{where}[{k!r}]")
    else:
        assert a == b or (a != a and b != b), where  # NaN equals NaN here


@pytest.mark.parametrize("name", ["Grey_sphere_r01", "White_flat_r01", "Pink_paraboloid_r02"])
@pytest.mark.parametrize("max_depth", [None, 1.5e-3])
def test_tared_equals_a_tared_prepare(name, max_depth):
    trace = read_trace(EXAMPLE / f"{name}.csv")
    kind = name.split("_")[1]
    tip = Tip(kind, radius=0.01 if kind != "paraboloid" else 0.0117)
    model = ModelSpec(tip, nu=0.3)
    data = prepare(trace, model, max_depth=max_depth)
    assert data.tare == 0.0 and data.baseline.level != 0.0
    got, want = tared(data), prepare(trace, model, max_depth=max_depth, tare=True)
    assert got.tare == want.tare == pytest.approx(data.baseline.level)
    _same(got, want, "data")
    assert tared(got) is got  # tared already


def test_fit_data_prepared_with_other_options_are_refused():
    from dataclasses import replace

    import palpbayes as pb
    from palpbayes.campaign.fitjob import check_fittable, fit_trace
    from palpbayes.errors import InputError

    trace = pb.read(EXAMPLE / "Grey_sphere_r01.csv", tip="sphere", radius=0.01)
    options = pb.fit_options(method="lsq")
    data = check_fittable(trace, options)
    assert fit_trace(trace, options, data=data).rows[0]["E_pa"] > 0
    for other in (replace(options, max_depth=1e-3), replace(options, f_unc=0.5),
                  replace(options, fit_fraction=0.3)):
        with pytest.raises(InputError, match="prepared with other options"):
            fit_trace(trace, other, data=data)
