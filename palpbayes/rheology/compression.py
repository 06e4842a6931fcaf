"""The modulus a compression test would report for a fitted relaxation modulus.

The ground truth of the paper is an Instron compression of the specimen at a constant cross-head
speed (50 mm/min), read as the slope of stress against strain over a strain window
(:func:`palpbayes.compression.fit_modulus`).  For a viscoelastic material that slope depends on
the speed: a cylinder of height H compressed from rest at strain rate r = v/H carries the
uniaxial stress (DESIGN §9)

    sigma(t) = r·∫_0^t E(s) ds = r·(1 − nu²)·∫_0^t E*(s) ds,    strain eps = r·t,

with the uniaxial relaxation modulus E(t) = (1 − nu²)·E*(t) (the correspondence principle
with a constant Poisson ratio).  Each posterior draw's stress–strain curve is read by the
ground truth's own rule (toe-compensated least-squares slope over the same window), so a
palpation at any speed is set beside the compression test's number, interval included.
Assumes a lubricated, unconfined compression of a specimen much wider than it is high.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..compression import DEFAULT_STRAIN_WINDOW, fit_modulus, toe_compression
from ..contact import youngs_modulus
from ..contact.viscoelastic import PowerLawKernel, PronyKernel, hereditary_force
from ..errors import InputError
from ..io.instron import CompressionTest

__all__ = ["compression_moduli", "PAPER_COMPRESSION_SPEED", "CURVE_POINTS"]

#: [m/s] Cross-head speed of the paper's Instron tests (50 mm/min).
PAPER_COMPRESSION_SPEED = 50e-3 / 60.0
#: Points of each simulated stress–strain curve (up to twice the window's upper strain).
CURVE_POINTS = 400


def compression_moduli(kernels: Sequence[PowerLawKernel | PronyKernel], nu: float,
                       speed: float = PAPER_COMPRESSION_SPEED, height: float | None = None,
                       strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
                       toe: float = 0.0) -> np.ndarray:
    """Young's modulus [Pa] the compression test's rule reads for each relaxation kernel.

    Parameters
    ----------
    kernels
        Relaxation moduli E*(t) [Pa] (plane-strain, as the palpation fit reports them).
    nu
        Poisson's ratio [-]: E(t) = (1 − nu²)·E*(t).
    speed
        [m/s] Cross-head speed (default the paper's 50 mm/min).
    height
        [m] Specimen height (the strain rate is speed/height).
    strain_window
        [-] The ground truth's fit window (default 0–5 %).
    toe
        [m] Slack of the test before full contact (the quadratic toe of
        :func:`~palpbayes.compression.toe_compression`; the ground truth's analysis
        reports it per test as ``strain_toe``·height).  With a toe the strain history is
        not a constant-rate ramp: the stress is the hereditary integral of the toe's strain
        history (:func:`~palpbayes.contact.viscoelastic.hereditary_force`), read with the
        rule's toe compensation, as the test itself is.  On a power law of alpha 0.12 a toe
        of 0.2 mm in 30 mm lowers the reading by 1 %.

    Returns
    -------
    numpy.ndarray
        One modulus [Pa] per kernel.

    Raises
    ------
    InputError
        A missing or non-positive height or speed.
    """
    if height is None or not (np.isfinite(height) and height > 0):
        raise InputError(f"the compression modulus needs the specimen height [m] (got "
                         f"{height!r}): give --thickness or the manifest's thickness_m")
    if not (np.isfinite(speed) and speed > 0):
        raise InputError(f"compression speed {speed!r} m/s must be positive")
    if not (np.isfinite(toe) and 0.0 <= toe < 0.5 * height):
        raise InputError(f"compression toe {toe!r} m must be >= 0 and below half the height")
    rate = speed / height
    eps = np.linspace(0.0, 2.0 * float(strain_window[1]) + 2.0 * toe / height, CURVE_POINTS)
    t = eps / rate
    out = np.empty(len(kernels))
    for i, kernel in enumerate(kernels):
        if toe > 0:
            strain = toe_compression(eps * height, toe) / height
            stress = youngs_modulus(hereditary_force(t, strain, 1.0, 1.0, kernel), nu)
        else:
            stress = rate * youngs_modulus(kernel.integral(t), nu)
        test = CompressionTest(time_s=t, compression_m=eps * height, load_n=stress,
                               specimen="model", material="", area_m2=1.0, height_m=height,
                               source="the fitted relaxation modulus")
        out[i] = fit_modulus(test, strain_window).E_pa
    return out
