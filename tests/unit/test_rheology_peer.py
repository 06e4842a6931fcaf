"""PyFMRheo-compatible reading (palpbayes.rheology.peer): straight ramps, the fixed drag, and
what a fit of such a trace returns when the tip really moved at constant speed (the truth)
and on the peer's own map (its notebook's reading, not the recording's)."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.contact import Tip
from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.errors import InputError
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.peer import PYFMRHEO_DRAG, nominal_ramps, pyfmrheo_compatible
from palpbayes.sim import simulate_viscoelastic

TIP = Tip("paraboloid", radius=5e-6)
MAP = "afm-files/pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map"


def _cycle(seed: int, rate: float = 5000.0):
    """A map-like cycle at constant speed (20 µm/s, 0.5 µm deep, 2 µm of approach), E0* 200
    Pa, alpha 0.3, white noise 15 pN, with the notebook's drag added."""
    tr = simulate_viscoelastic(PowerLawKernel(200.0, 0.3), TIP, depth=0.5e-6, speed=20e-6,
                               hold_time=0.0, rate=rate, approach=2e-6, z_surf=1e-5,
                               noise_sd=15e-12, rng=seed)
    v = np.gradient(tr.z, tr.time)
    return tr.replace(force=tr.force + PYFMRHEO_DRAG * (-v))


def test_a_trace_without_segment_codes_gets_them_from_the_motion():
    """The motion calls the turn (3 samples of 1,251) a hold; the peer's reading gives it to
    the two ramps, as the recorded codes do."""
    tr = _cycle(3)
    assert set(np.unique(nominal_ramps(tr.replace(segment=None)).segment)) == {0, 1, 2}
    like, _ = pyfmrheo_compatible(tr.replace(segment=None))
    mine, _ = pyfmrheo_compatible(tr)
    np.testing.assert_array_equal(like.segment, tr.segment)
    np.testing.assert_allclose(like.z, mine.z, rtol=0, atol=1e-15)
    np.testing.assert_allclose(like.force, mine.force, rtol=0, atol=1e-22)


def test_nominal_ramps_are_straight_between_each_segments_ends():
    tr = _cycle(0)
    wobble = tr.replace(z=tr.z + 2e-8 * np.sin(tr.time * 300.0))
    out = nominal_ramps(wobble)
    for code in (0, 2):
        m = tr.segment == code
        t, z = out.time[m], out.z[m]
        assert z[0] == wobble.z[m][0] and z[-1] == wobble.z[m][-1]
        np.testing.assert_allclose(np.diff(z) / np.diff(t), (z[-1] - z[0]) / (t[-1] - t[0]),
                                   rtol=1e-9)
    np.testing.assert_array_equal(out.force, wobble.force)
    np.testing.assert_array_equal(out.segment, wobble.segment)


def test_the_fixed_drag_is_taken_off_the_force():
    """b·(−dz/dt) with each ramp's own speed, (last − first height)/(last − first time), on
    every sample of it, the two samples at the turn included."""
    tr = _cycle(1)
    like, kw = pyfmrheo_compatible(tr)
    for code in (0, 2):
        m = tr.segment == code
        v = (tr.z[m][-1] - tr.z[m][0]) / (tr.time[m][-1] - tr.time[m][0])
        np.testing.assert_allclose(like.force[m], tr.force[m] + PYFMRHEO_DRAG * v, rtol=0,
                                   atol=1e-22)
    assert kw == {"segments": "approach,retract", "drag": False, "t0": 1.0}


def test_on_a_constant_speed_cycle_the_compatible_reading_recovers_the_truth():
    """Where the tip did move at constant speed the peer's reading is the recording's: the
    90 % intervals cover E0* = 200 Pa and alpha = 0.3 on each of three seeds (measured
    medians within 3 % and 0.01)."""
    for seed in range(3):
        like, kw = pyfmrheo_compatible(_cycle(seed))
        fit = fit_rheology(like, "power-law", **kw)
        e0 = np.quantile(fit.draws["E0"], [0.05, 0.95])
        al = np.quantile(fit.draws["alpha"], [0.05, 0.95])
        assert e0[0] <= 200.0 <= e0[1], (seed, e0)
        assert al[0] <= 0.3 <= al[1], (seed, al)


def test_the_command_line_reads_as_the_peer_and_says_so(tmp_path, capsys):
    """``fit --rheology power-law --peer-compatible pyfmrheo``: the row is the API's fit of
    :func:`pyfmrheo_compatible`'s trace, marked ``peer_compatible``; the segments are the
    peer's (approach, retract)."""
    import pandas as pd

    from palpbayes.cli import main
    from palpbayes.io.trace_csv import write_trace
    tr = _cycle(4, rate=2000.0)
    path = write_trace(tr.replace(trace_id="c4"), tmp_path / "c4.csv", float_format="%.15g")
    assert main(["fit", str(path), "--rheology", "power-law", "--peer-compatible", "pyfmrheo",
                 "--tip", "paraboloid", "--radius", "5e-6", "--no-progress",
                 "--out", str(tmp_path / "r")]) == 0
    assert "c4: read as pyfmrheo reads it (to compare, not to report); E0* " in (
        capsys.readouterr().out)
    row = pd.read_csv(tmp_path / "r" / "rheology.csv").iloc[0]
    assert row["peer_compatible"] == "pyfmrheo" and row["segments"] == "approach,retract"
    like, kw = pyfmrheo_compatible(tr)
    api = fit_rheology(like, "power-law", rng=0, **kw)
    assert row["E0_star_pa"] == pytest.approx(float(np.median(api.draws["E0"])), rel=1e-6)
    assert row["alpha"] == pytest.approx(float(np.median(api.draws["alpha"])), abs=1e-6)


def test_bad_input_is_named():
    tr = _cycle(2)
    with pytest.raises(InputError, match="a hold"):  # a triangle's closed forms
        pyfmrheo_compatible(simulate_viscoelastic(
            PowerLawKernel(200.0, 0.3), TIP, depth=0.5e-6, speed=20e-6, hold_time=0.1,
            rate=2000.0, approach=2e-6, noise_sd=15e-12, rng=0))
    with pytest.raises(InputError, match="a hold"):  # the hold left out: a gap in time
        held = simulate_viscoelastic(PowerLawKernel(200.0, 0.3), TIP, depth=0.5e-6,
                                     speed=20e-6, hold_time=0.1, rate=2000.0, approach=2e-6,
                                     noise_sd=15e-12, rng=0)
        pyfmrheo_compatible(held.segments("approach,retract"))
    with pytest.raises(InputError, match="approach and the retract"):
        pyfmrheo_compatible(tr.segments("approach"))
    with pytest.raises(InputError, match="drag"):
        pyfmrheo_compatible(tr, drag=-1.0)
    one = np.ones(tr.n_points, dtype=bool)
    one[np.flatnonzero(tr.segment == 2)[1:]] = False  # a retract of one sample
    with pytest.raises(InputError, match="a ramp's speed needs two"):
        pyfmrheo_compatible(tr.replace(time=tr.time[one], z=tr.z[one], force=tr.force[one],
                                       segment=tr.segment[one]))


@pytest.mark.slow
def test_on_the_peers_map_the_compatible_reading_moves_towards_the_peer(shared_data):
    """Curve 0 of PyFMRheo's map: its notebook reads alpha 0.168 (0.17-0.20 over its own
    contact-window and fit-range choices), its numerical model 0.386, palpbayes 0.40
    (`benchmarks/bench_visco_peer.py`).  Read as the notebook reads it (straight ramps, drag
    fixed) palpbayes gives 0.23 (measured): the constant speeds are most of the gap."""
    from palpbayes.io.afm import read_afm
    path = shared_data(MAP)
    tr = read_afm(path, tip=TIP, curves=[0], segments="all")[0]
    own = fit_rheology(tr, "power-law", segments="approach,retract")
    like, kw = pyfmrheo_compatible(tr)
    peerish = fit_rheology(like, "power-law", **kw)
    a_own = float(np.median(own.draws["alpha"]))
    a_like = float(np.median(peerish.draws["alpha"]))
    assert 0.36 < a_own < 0.44
    assert 0.17 < a_like < 0.30 and a_own - a_like > 0.1


def test_the_command_line_offers_the_peers_the_module_imitates():
    from palpbayes.cli.rheology import PEER_NAMES
    from palpbayes.rheology.peer import PEERS
    assert PEER_NAMES == PEERS
    with pytest.raises(InputError, match="can read a trace as pyfmrheo"):
        from palpbayes.rheology.peer import peer_compatible
        peer_compatible(_cycle(0), "nanite")
    with pytest.raises(InputError, match="can read a trace as pyfmrheo"):  # before any fit
        from palpbayes.rheology.results import rheology_options
        rheology_options("power-law", peer="nanite")
