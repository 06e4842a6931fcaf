"""PyFMRheo's Ting fit, run inside the peer's own virtual environment (never palpbayes').

Called by ``bench_visco_peer.py`` with the peer's interpreter::

    /tmp/pyfm/bin/python benchmarks/pyfmrheo_worker.py map FILE.jpk-force-map
    /tmp/pyfm/bin/python benchmarks/pyfmrheo_worker.py sim CURVES.npz

It prints one JSON line per (curve, variant): the peer's E0 [Pa] (Young's modulus, nu 0.5),
its fluidity exponent betaE, its contact time [s] from the start of the approach, or the error.

Settings: PyFMRheo's ``examples/ViscoelasticFitExample.ipynb`` (commit 24a33845), the
notebook that fits this map: paraboloid R = 5 µm, nu 0.5, contact point by the ratio of
variances (window 400 nm) refined by a Hertz fit, t0 = 1 s, viscous drag fixed at
2.5e-6 N·s/m, the data from 1 µm above the contact, 300 points, the analytical Ting model.
The notebook's dictionary lacks ``correct_offset``, which pyfmrheo 0.1.3 reads; it is set to
False (what the notebook's run did).  The variants change one setting each, as the notebook
allows: the contact point's window (x0.5, x2), the fit range above the contact (0.5, 2 µm),
the speeds fitted from the data (``compute_v_flag``), the numerical Ting model (the
measured indentation history instead of constant speeds; pyfmrheo 0.1.3 calls ``np.trapz``,
gone in numpy 2, so ``np.trapezoid`` is aliased to it here), and "exact 2F1": the
analytical model with scipy's hypergeometric function in place of the peer's approximation
(``hyp2f1_apprx``, Butler & Wood's Laplace approximation, stated for 0 < a < c and called
with a = 1 > c = 1/2; at alpha 0.4 it turns the retract's force negative 2 ms after the
turn, where Ting's solution, by quadrature, is +418 pN).

Simulated curves (``sim``): an ``.npz`` with, per curve ``k``, arrays ``t{k}`` [s], ``z{k}``
(tip height, up) [m], ``f{k}`` [N] and ``s{k}`` (0 approach, 2 retract), and the scalar
``spring``: they become a pyfmreader ForceCurve with deflection f/spring and piezo height
(down) deflection − z, so that PyFMRheo's indentation is −z + const.
"""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

if not hasattr(np, "trapz"):  # pyfmrheo 0.1.3's numerical model, numpy >= 2
    np.trapz = np.trapezoid  # noqa: NPY201 (the peer calls np.trapz)

warnings.filterwarnings("ignore")

NOTEBOOK = {
    "contact_model": "paraboloid", "tip_param": 5e-06, "curve_seg": "extend",
    "correct_tilt": False, "correct_offset": False, "tilt_min_offset": 1e-08,
    "tilt_max_offset": 1e-06, "poisson": 0.5, "poc_method": "RoV", "poc_win": 4e-07,
    "max_ind": 0.0, "min_ind": 0.0, "max_force": 0.0, "min_force": 0.0,
    "fit_range_type": "full", "vdragcorr": False, "polyordr": 2, "rampspeed": 0.0,
    "compute_v_flag": False, "t0": 1, "d0": 0.0, "slope": 0.0, "auto_init_E0": True,
    "E0": 1000, "tc": 0.0, "auto_init_betaE": True, "fluid_exp": 0.2, "f0": 0.0,
    "vdrag": 2.5e-06, "model_type": "analytical", "smoothing_win": 5, "contact_offset": 1e-6,
    "fit_line": False, "downsample_flag": True, "pts_downsample": 300,
    "offset_type": "percentage", "max_offset": 0.3, "min_offset": 0,
}
VARIANTS = {
    "notebook": {},
    "poc_win 200 nm": {"poc_win": 2e-7},
    "poc_win 800 nm": {"poc_win": 8e-7},
    "range 0.5 um": {"contact_offset": 0.5e-6},
    "range 2 um": {"contact_offset": 2e-6},
    "speeds from data": {"compute_v_flag": True},
    "no drag": {"vdrag": 0.0},
    "exact 2F1": {"_exact_hyp2f1": True},
    "exact 2F1, no drag": {"_exact_hyp2f1": True, "vdrag": 0.0},
    "exact 2F1, poc_win 200 nm": {"_exact_hyp2f1": True, "poc_win": 2e-7},
    "exact 2F1, poc_win 800 nm": {"_exact_hyp2f1": True, "poc_win": 8e-7},
    "exact 2F1, range 0.5 um": {"_exact_hyp2f1": True, "contact_offset": 0.5e-6},
    "exact 2F1, range 2 um": {"_exact_hyp2f1": True, "contact_offset": 2e-6},
    "numerical": {"model_type": "numerical"},
    "numerical, poc_win 200 nm": {"model_type": "numerical", "poc_win": 2e-7},
    "numerical, poc_win 800 nm": {"model_type": "numerical", "poc_win": 8e-7},
    "numerical, range 0.5 um": {"model_type": "numerical", "contact_offset": 0.5e-6},
    "numerical, range 2 um": {"model_type": "numerical", "contact_offset": 2e-6},
}


def _fit(make_curve, params: dict) -> dict:
    import pyfmrheo.models.ting as ting_module
    from pyfmrheo.routines.TingFit import doTingFit
    from pyfmrheo.utils.signal_processing import hyp2f1_apprx
    from scipy.special import hyp2f1
    params = dict(params)
    # "exact 2F1": the analytical retract with scipy's 2F1 in place of the peer's Laplace
    # approximation (Butler & Wood 2002, stated for 0 < a < c; the retract calls it with
    # a = 1 > c = 1/2)
    exact = params.pop("_exact_hyp2f1", False)
    ting_module.hyp2f1_apprx = (lambda a, b, c, x: hyp2f1(a, b, c, x)) if exact else hyp2f1_apprx
    curve = make_curve()
    ext = curve.extend_segments[0][1]
    try:
        ting, _ = doTingFit(curve, params)
    except Exception as exc:  # the peer's own failure, reported per curve
        return {"error": f"{type(exc).__name__}: {exc}"[:200]}
    ind = ext.indentation
    t_contact = float(ext.time[int(np.argmin(np.abs(ind)))] + ting.tc)
    return {"E0": float(ting.E0), "beta": float(ting.betaE), "t_contact": t_contact}


def _file_curves(path: str):
    from pyfmreader import loadfile
    f = loadfile(path)
    md = f.filemetadata
    base = {"height_channel": md["height_channel_key"],
            "def_sens": md["defl_sens_nmbyV"] / 1e9, "k": md["spring_const_Nbym"]}

    def make(i):
        def curve():
            c = f.getcurve(i)
            c.preprocess_force_curve(base["def_sens"], base["height_channel"])
            if md["file_type"] in ("jpk-force", "jpk-force-map", "jpk-qi-data"):
                c.shift_height()
            return c
        return curve
    n = len(f.filemetadata["curve_properties"]) if "curve_properties" in md else 16
    return [make(i) for i in range(n)], base


def _sim_curves(path: str):
    from pyfmreader.utils.forcecurve import ForceCurve
    from pyfmreader.utils.segment import Segment
    data = np.load(path)
    k = float(data["spring"])
    n = sum(1 for key in data.files if key.startswith("t"))

    def segment(kind, code, t, z, f, sid):
        s = Segment("sim", str(sid), kind)
        s.time = t - t[0]
        s.vdeflection = f / k
        s.zheight = s.vdeflection - z
        v = (z[-1] - z[0]) / (t[-1] - t[0])
        s.velocity = v * 1e9  # nm/s, negative on the approach as in JPK files
        s.segment_metadata = {"duration": float(t[-1] - t[0] + (t[1] - t[0])),
                              "baseline_measured": False}
        return s

    def make(i):
        def curve():
            t, z, f, s = (data[f"{c}{i}"] for c in "tzfs")
            c = ForceCurve(i, "sim")
            a, r = s == 0, s == 2
            c.extend_segments.append(("0", segment("Approach", 0, t[a], z[a], f[a], 0)))
            c.retract_segments.append(("1", segment("Retract", 2, t[r], z[r], f[r], 1)))
            return c
        return curve
    return [make(i) for i in range(n)], {"height_channel": "measuredHeight", "def_sens": 1.0,
                                         "k": k}


def main(argv: list[str]) -> int:
    mode, path = argv[0], argv[1]
    names = argv[2].split(";") if len(argv) > 2 else list(VARIANTS)
    curves, base = (_file_curves if mode == "map" else _sim_curves)(path)
    for i, make in enumerate(curves):
        for name in names:
            row = _fit(make, {**NOTEBOOK, **base, **VARIANTS[name]})
            print(json.dumps({"curve": i, "variant": name, **row}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
