"""Synthetic palpation traces, Instron compression curves and whole campaigns (one import).

Re-exports :mod:`palpbayes.simulate_core` (one trace, one compression test: the force model,
noise and misspecification knobs, the paper's numbers) and :mod:`palpbayes.simulate_campaign`
(campaign folders, repeated palpation with rest-time stiffening).  Imports flow one way:
``simulate`` -> ``simulate_campaign`` -> ``simulate_core``.
"""

from __future__ import annotations

from .campaign import (
    rest_modulus,
    simulate_campaign,
    simulate_palpation_series,
)
from .trace import (
    PAPER_MATERIALS,
    PAPER_ROBOT_ESTIMATES,
    PAPER_SURFACE_ERROR_M,
    PAPER_TIPS,
    PP_TO_SIGMA,
    STIFFENING_STRAIN0,
    Material,
    RobotEstimate,
    ar1_noise,
    onset_force_profile,
    paper_robot_estimates_frame,
    sigma_from_pp,
    simulate_compression_test,
    simulate_trace,
    solve_series_compliance,
    stiffening_factor,
    toe_compression,
    true_force,
    write_compression_export,
)

__all__ = [
    "PP_TO_SIGMA",
    "sigma_from_pp",
    "Material",
    "RobotEstimate",
    "PAPER_MATERIALS",
    "PAPER_TIPS",
    "PAPER_ROBOT_ESTIMATES",
    "PAPER_SURFACE_ERROR_M",
    "paper_robot_estimates_frame",
    "STIFFENING_STRAIN0",
    "stiffening_factor",
    "true_force",
    "onset_force_profile",
    "solve_series_compliance",
    "ar1_noise",
    "simulate_trace",
    "toe_compression",
    "simulate_compression_test",
    "write_compression_export",
    "simulate_campaign",
    "simulate_palpation_series",
    "rest_modulus",
]
