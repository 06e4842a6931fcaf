"""Palpations with a misfit the user did not model: the model-form calibration's traces.

Each scenario is a paper-like palpation (a paraboloid or sphere tip 3 mm into a silicone-like
specimen, nu 0.45, 50 mm/min) with one physical effect that the half-space contact law lacks,
and with the uncertainty budget's inputs drawn from the budget's own distributions
(:class:`palpbayes.bayes.BudgetSpec` defaults: Poisson ratio ±0.05, tip radius ±1 %, force
gain 1 %, compliance up to 2 µm/N), so that a correct model with its budget covers the true E
in 90 % of the traces.  The trace carries no thickness: the user did not give it.

=================  ===========================================================================
scenario           the effect (varied over the traces)
=================  ===========================================================================
``well``           none: the half-space law is right
``layer_bonded``   a layer of 20–30 mm bonded to a rigid base, depth 10 % of it
``layer_free``     the same layer lying on the base without friction
``stiffening``     strain stiffening, beta 3–6 on a 30 mm specimen (secant modulus ×1.16–1.35
                   at 10 % strain; :func:`palpbayes.sim.force.stiffening_factor`)
``onset``          a gradual onset, 20–80 mN over 0.1–0.3 mm (a soft skin, adhesion;
                   :func:`palpbayes.sim.force.onset_force_profile`)
``blunt``          a paraboloid apex worn flat over 1–3 mm radius
                   (:func:`palpbayes.sim.force.blunted_paraboloid_shape`)
=================  ===========================================================================
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..contact import Tip, effective_modulus
from ..errors import InputError
from ..trace import IndentationTrace
from .trace import simulate_trace

__all__ = ["MISFIT_SCENARIOS", "MISFIT_NU", "MISFIT_E", "misfit_trace"]

#: The scenarios of :func:`misfit_trace`.
MISFIT_SCENARIOS = ("well", "layer_bonded", "layer_free", "stiffening", "onset", "blunt")
#: Nominal Poisson ratio (what the fit is told) [-].
MISFIT_NU = 0.45
#: True Young's modulus [Pa].
MISFIT_E = 50e3

_TIPS = (Tip("paraboloid", radius=0.0117), Tip("sphere", radius=0.010))


def misfit_trace(scenario: str, index: int, *, rate: float = 200.0
                 ) -> tuple[IndentationTrace, Tip]:
    """Trace ``index`` of ``scenario`` (module docstring) and the nominal tip to fit it with.

    Everything is drawn from ``numpy.random.default_rng([index, k])`` with k the scenario's
    position in :data:`MISFIT_SCENARIOS`: the same index gives the same trace.  The truth is
    in ``trace.metadata`` (``E_true`` = :data:`MISFIT_E`) together with the drawn budget
    inputs ``nu_true``, ``radius_factor``, ``gain``, ``compliance_true``.

    Parameters
    ----------
    scenario
        One of :data:`MISFIT_SCENARIOS`.
    index
        Trace number (>= 0).
    rate
        [Hz] Sample rate (200 Hz keeps a calibration of hundreds of fits short; the paper's
        sensor runs at 800).

    Returns
    -------
    (IndentationTrace, Tip)
        The trace (no thickness; the truth in its metadata) and the nominal tip.
    """
    if not (isinstance(index, int | np.integer) and index >= 0):
        raise InputError(f"misfit trace index {index!r} must be an integer >= 0")
    if scenario not in MISFIT_SCENARIOS:
        raise InputError(f"unknown misfit scenario {scenario!r}; use one of "
                         f"{', '.join(MISFIT_SCENARIOS)}")
    rng = np.random.default_rng([index, MISFIT_SCENARIOS.index(scenario)])
    nominal = _TIPS[0] if scenario == "blunt" else _TIPS[index % 2]
    nu = rng.uniform(MISFIT_NU - 0.05, MISFIT_NU + 0.05)
    radius_factor = rng.uniform(0.99, 1.01)
    gain = rng.normal(1.0, 0.01)
    compliance = rng.uniform(0.0, 2e-6)
    u = rng.uniform()
    tip = nominal.scaled(radius_factor)
    kw: dict = {"depth": 3e-3, "base": None}
    if scenario in ("layer_bonded", "layer_free"):
        h = 0.020 + 0.010 * u
        kw = {"thickness": h, "depth": 0.1 * h, "base": scenario.removeprefix("layer_")}
    elif scenario == "stiffening":
        kw = {"thickness": 0.030, "base": None, "stiffening": 3.0 + 3.0 * u}
    elif scenario == "onset":
        kw.update(onset_force=0.02 + 0.06 * u, onset_length=1e-4 + 2e-4 * rng.uniform())
    elif scenario == "blunt":
        kw.update(apex_flat_radius=1e-3 + 2e-3 * u)
    # a force-sensor gain g scales the contact force as E*·g would
    trace = simulate_trace(MISFIT_E * gain, tip, nu=nu, rate=rate, compliance=compliance,
                           rng=rng, trace_id=f"{scenario}-{index:03d}", **kw)
    meta = dict(trace.metadata, E_true=MISFIT_E, Estar_true=effective_modulus(MISFIT_E, nu),
                nu_true=nu, radius_factor=radius_factor,
                gain=gain, scenario=scenario)
    return replace(trace, thickness=None, metadata=meta), nominal
