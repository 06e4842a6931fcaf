"""A force in another unit than the one declared, seen without a declared sensor noise (issue 58,
item 1): the tip's size says which instrument pressed, and what its sensor and its specimens
read (palpbayes.forcescale).

Measured on every real recording of ../shared/data and every trace of the shipped example:
none is doubted as read, every one is doubted, with the right factor, when its force is read
1,000 times too small; read 1,000 times too large, every robot trace is.
"""

from __future__ import annotations

import doctest
from dataclasses import replace
from pathlib import Path

import pytest

import palpbayes.forcescale as forcescale
from palpbayes.campaign.fitjob import FitOptions, check_fittable, force_scale_flag
from palpbayes.contact import Tip
from palpbayes.errors import PalpbayesError
from palpbayes.flagcodes import flag_columns
from palpbayes.forcescale import (
    BAYES_FACTOR,
    force_scale_doubt,
    force_scale_flag_text,
    tip_scale,
)
from palpbayes.io.manifest import load_trace, read_manifest
from palpbayes.io.recording import read_recording

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "data" / "example-campaign" / "manifest.csv"


def test_doctests():
    assert doctest.testmod(forcescale).failed == 0


def test_the_readme_example_is_doubted_with_the_factor_named():
    # a 10 mm sphere, 60 kPa, the paper's 48 mN p-p sensor, its force in N declared as mN
    d = force_scale_doubt(0.01, 60.0, 48e-6)
    assert d is not None and d.factor == 1e3 and d.bayes_factor >= BAYES_FACTOR
    assert d.instrument.name.startswith("a robot's")
    text = force_scale_flag_text(d, "sphere R=10 mm")
    assert text.startswith("force scale: the force reads 1,000 times too small")
    head = text[:text.find(" (")]
    assert "--force-unit" in head  # what the console prints of a flag
    assert flag_columns(text)["flag_codes"] == "force_scale"  # one flag, coded
    assert flag_columns(text)["flag_level"] == "warning"


@pytest.mark.parametrize("scale, modulus, noise", [
    (0.01, 60e3, 48e-3),      # the README's robot, as it should read
    (0.01, 1e3, 1e-3),        # soft tissue on a bench load cell
    (0.01, 5e6, 0.1),         # a rubber on a robot's sensor
    (10e-6, 500.0, 100e-12),  # an AFM cantilever on a cell
    (2e-9 * 1e3, 1e9, 2e-9),  # a sharp AFM cone (scale = its depth) on a stiff polymer
    (100e-6, 20e3, 5e-9),     # a micro-indenter on a gel
])
def test_plausible_forces_are_not_doubted(scale, modulus, noise):
    assert force_scale_doubt(scale, modulus, noise) is None


@pytest.mark.parametrize("factor", [1e-3, 1e3, 1e-6, 1e6])
def test_a_robot_force_off_by_powers_of_1000_is_doubted_with_the_factor(factor):
    d = force_scale_doubt(0.01, 60e3 * factor, 48e-3 * factor)
    assert d is not None and d.factor == pytest.approx(1 / factor)


def test_nothing_to_weigh_is_not_doubted():
    for modulus in (0.0, -5.0, float("nan"), float("inf")):
        assert force_scale_doubt(0.01, modulus, 48e-6) is None
    # without a measured noise E alone is not weighed: a 1 GPa polymer under an AFM would
    # read as a micro-indenter's force 1,000 times too large
    assert force_scale_doubt(0.01, 60.0, None) is None
    assert force_scale_doubt(2e-6, 1e9, None) is None
    assert force_scale_doubt(float("nan"), 60.0, 48e-6) is None
    assert tip_scale(None, 3e-3) == 3e-3 and tip_scale(0.01, 3e-3) == 0.01


def _real_traces(shared: Path):
    """(label, trace, is_robot) of every real AFM curve the readers return and every trace of
    the shipped example."""
    out = []
    for folder in ("afm-curves", "afm-files"):
        for f in sorted((shared / folder).iterdir()):
            if f.suffix in (".md", ".txt") or f.name == "references.csv":
                continue
            tip = Tip("paraboloid", radius=5e-6 if "pyfmrheo" in f.name else 10e-6)
            try:
                traces = read_recording(f, tip=tip)
            except PalpbayesError:
                continue  # a file the readers refuse (tested elsewhere)
            out += [(f"{f.name}#{i}", t, False) for i, t in enumerate(traces)]
    man = read_manifest(EXAMPLE)
    out += [(f"example {r['trace_id']}", load_trace(r), True) for _, r in man.iterrows()]
    return out


def _flag(trace, factor: float, nu: float):
    scaled = replace(trace, force=trace.force * factor)
    opts = FitOptions(method="lsq", nu=nu)
    return force_scale_flag(check_fittable(scaled, opts), opts)


def test_every_real_and_shipped_recording(shared_data):
    shared = shared_data("afm-curves", files=["map1d-curve7.csv"]).parent
    shared_data("afm-files")
    rows = []
    for label, trace, robot in _real_traces(shared):
        nu = 0.3 if robot else 0.5
        try:
            as_read = _flag(trace, 1.0, nu)
        except PalpbayesError:
            continue  # no contact, a depth beyond the tip: refused before any fit
        rows.append((label, robot, as_read, _flag(trace, 1e-3, nu), _flag(trace, 1e3, nu)))
    robots = [r for r in rows if r[1]]
    afm = [r for r in rows if not r[1]]
    assert len(robots) == 27 and len(afm) >= 20
    assert [r[0] for r in rows if r[2] is not None] == []  # none doubted as read
    small = [r for r in rows if r[3] is None or "1,000 times too small" not in r[3]]
    assert small == []  # every one doubted read 1,000 times too small, with the factor named
    large = [r[0] for r in robots if r[4] is None or "1,000 times too large" not in r[4]]
    assert large == []  # every robot trace read 1,000 times too large
