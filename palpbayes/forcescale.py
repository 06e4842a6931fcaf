"""Is a trace's force in the unit it was declared in?  What an instrument at a tip's scale reads.

A force read in the wrong unit (newtons declared as millinewtons) multiplies the force, its
noise and E by one power of 1,000.  The fit cannot see it: the contact law is linear in E, so a
trace scaled by 1,000 is fitted as well as the true one, converges and passes every model check
(``E 60 Pa`` for a 60 kPa block, ``model_ok True``).  Without a declared sensor noise
(``--noise-pp``, :func:`palpbayes.sensor_noise.noise_scale_mismatch`) only what the tip says
about the instrument is left: a 10 mm sphere is a robot's or a bench indenter's, a 10 µm sphere
an AFM cantilever's, and each kind of instrument reads a known range of sensor noise and of modulus.

The model (:data:`INSTRUMENTS`): three kinds of instrument, each with the range of tip sizes it
uses and, as log-normal laws (median, sd in decades), the peak-to-peak force noise of its sensor
before contact and the modulus it is used on:

================  ================  ==================  =================
instrument        tip size [m]      noise p-p           E
================  ================  ==================  =================
AFM cantilever    1e-8 .. 5e-5      150 pN, 0.6 dec.    10 kPa, 2.0 dec.
micro-indenter    1e-6 .. 1e-3      10 nN, 1.3 dec.     10 kPa, 1.3 dec.
macro indenter    1e-4 .. 0.1       5 mN, 1.0 dec.      100 kPa, 1.3 dec.
================  ================  ==================  =================

Where they come from: an AFM cantilever's thermal noise is sqrt(k_B·T·k) = 6–64 pN for
k = 0.01–1 N/m (±3 sd: 40–400 pN p-p; the real curves of ``../shared/data`` read 31–160 pN);
fibre-optic and capacitive micro-indenters (probe radii 3–250 µm) resolve nN to tens of nN; a
robot's wrist force/torque sensor resolves 3–60 mN (ATI Nano17 to Gamma; the paper's 48 mN
p-p), a bench load cell or texture analyser 0.1–1 mN.  Indentation is used on cells and gels
(0.1–100 kPa), tissue (1–100 kPa), foams and rubbers (10 kPa–10 MPa).  The widths are wide on
purpose: the model has to tell a factor 1,000 apart, not a material.

The decision (:func:`force_scale_doubt`): the tip's size L (:func:`tip_scale`: the radius, or
the indentation depth for a tip without one) selects the instruments whose range holds it
(equal weights; the nearest one outside every range); without a measured noise (no reliable
baseline) nothing is weighed. For each factor k ≠ 1 that a unit slip
makes (k = 10^±3, ±6, ±9: :data:`UNIT_FACTORS`, a slip of two prefixes taken 100 times rarer
than one), the likelihood of (k·noise, k·E) under that mixture is set against the likelihood of
(noise, E) as read. When the best k's odds reach :data:`BAYES_FACTOR` = 20 ("strong", Kass &
Raftery 1995, J. Am. Stat. Assoc. 90:773) the force is doubted, with that k named. A real
specimen that is unusually soft or stiff for its tip, measured with an unusually quiet or noisy
sensor, can be flagged: the flag says so, and it is a warning, never an error (unless
``--strict``). Measured on every real and shipped recording
(``tests/unit/test_forcescale.py``): none doubted as read; every one doubted with its force
read 1,000 times too small; read 1,000 times too large, every robot trace and 1 of the 24 AFM
curves (an AFM curve's force times 1,000 is what a micro-indenter reads).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .sensor_noise import noise_scale_mismatch
from .units import format_force, format_length, format_pressure

__all__ = ["Instrument", "INSTRUMENTS", "UNIT_FACTORS", "BAYES_FACTOR", "ForceScaleDoubt",
           "tip_scale", "force_scale_doubt", "force_scale_flag_text", "force_scale_flag",
           "FLAG_OPENING"]


@dataclass(frozen=True)
class Instrument:
    """A kind of instrument: the tip sizes it uses and what its force sensor and its specimens
    read, as log-normal laws in decades.

    Attributes
    ----------
    name
        What it is called in a message (``"a robot's or a bench indenter's"``).
    scale_lo, scale_hi
        [m] The tip sizes (radius, or depth for a tip without one) it uses.
    noise_pp, noise_dec
        [N] Median peak-to-peak force noise before contact, and its sd [decades].
    modulus, modulus_dec
        [Pa] Median modulus it is used on, and its sd [decades].
    """

    name: str
    scale_lo: float
    scale_hi: float
    noise_pp: float
    noise_dec: float
    modulus: float
    modulus_dec: float

    def log_density(self, noise_pp: float, modulus: float) -> float:
        """Log density of (log10 noise, log10 E) [per decade²]."""
        return (_log_normal(math.log10(modulus), math.log10(self.modulus), self.modulus_dec)
                + _log_normal(math.log10(noise_pp), math.log10(self.noise_pp), self.noise_dec))

    def distance(self, scale: float) -> float:
        """[decades] How far ``scale`` lies outside the tip sizes (0 inside)."""
        x = math.log10(scale)
        return max(math.log10(self.scale_lo) - x, x - math.log10(self.scale_hi), 0.0)


#: The instruments palpbayes meets (the module's table; the sources are in its docstring).
INSTRUMENTS = (
    Instrument("an AFM cantilever's", 1e-8, 5e-5, 150e-12, 0.6, 1e4, 2.0),
    Instrument("a micro-indenter's", 1e-6, 1e-3, 10e-9, 1.3, 1e4, 1.3),
    Instrument("a robot's or a bench indenter's", 1e-4, 0.1, 5e-3, 1.0, 1e5, 1.3),
)
#: The factors a unit slip multiplies the force by (one to three SI prefixes either way) and
#: their prior odds against a slip of one prefix: two prefixes off is 100 times rarer.
UNIT_FACTORS = {1e-3: 1.0, 1e3: 1.0, 1e-6: 1e-2, 1e6: 1e-2, 1e-9: 1e-4, 1e9: 1e-4}
#: The Bayes factor from which a unit slip is named ("strong": Kass & Raftery 1995).
BAYES_FACTOR = 20.0
#: How every flag of this module opens (its code in :mod:`palpbayes.flagcodes`: force_scale).
FLAG_OPENING = "force scale"


def _log_normal(x: float, mu: float, sd: float) -> float:
    return -0.5 * ((x - mu) / sd) ** 2 - math.log(sd) - 0.5 * math.log(2.0 * math.pi)


@dataclass(frozen=True)
class ForceScaleDoubt:
    """A force that reads as if it were in another unit.

    Attributes
    ----------
    factor
        The power of 1,000 the force would need to be multiplied by (1e3: it reads 1,000 times
        too small, a force in N declared as mN).
    bayes_factor
        How much more typical the force multiplied by ``factor`` is than as read.
    instrument
        The instrument the tip's size points to (the one that explains the corrected force
        best).
    scale, noise_pp, modulus
        [m], [N], [Pa] The tip's size, the noise before contact and the modulus as read.
    """

    factor: float
    bayes_factor: float
    instrument: Instrument
    scale: float
    noise_pp: float
    modulus: float


def tip_scale(radius: float | None, depth: float) -> float:
    """[m] The size of a tip that says which instrument it belongs to: its radius, or the
    indentation ``depth`` [m] for a tip without one (a cone, a power-law profile)."""
    if radius is not None and math.isfinite(radius) and radius > 0:
        return float(radius)
    return float(depth)


def _instruments(scale: float) -> tuple[Instrument, ...]:
    inside = tuple(i for i in INSTRUMENTS if i.distance(scale) == 0.0)
    return inside or (min(INSTRUMENTS, key=lambda i: i.distance(scale)),)


def _log_mixture(instruments: tuple[Instrument, ...], noise_pp: float, modulus: float) -> float:
    logs = [i.log_density(noise_pp, modulus) for i in instruments]
    top = max(logs)
    return top + math.log(sum(math.exp(v - top) for v in logs) / len(logs))


def force_scale_doubt(scale: float, modulus: float,
                      noise_pp: float | None = None) -> ForceScaleDoubt | None:
    """The unit slip a trace's force most likely carries, or None when the force is plausible.

    Parameters
    ----------
    scale
        [m] The tip's size (:func:`tip_scale`).
    modulus
        [Pa] The modulus the trace gives as read (a rough one is enough: the question is a
        factor 1,000).
    noise_pp
        [N] The peak-to-peak noise before contact.  None (no reliable baseline), or not finite
        and positive: nothing is weighed, E alone cannot tell a unit slip from an unusual
        material (an AFM on a 1 GPa polymer reads like a micro-indenter's force 1,000 times
        too large).

    Returns
    -------
    ForceScaleDoubt or None
        The factor k of :data:`UNIT_FACTORS` whose corrected (k·noise, k·E) is most typical
        of the instruments of this tip size, when its odds against the force as read are at
        least :data:`BAYES_FACTOR`; None otherwise, and when ``scale``, ``modulus`` or
        ``noise_pp`` is not finite and positive (nothing to weigh).

    Examples
    --------
    A 10 mm sphere pressing a 60 kPa block, its 48 mN sensor's force in N read as mN:

    >>> d = force_scale_doubt(0.01, 60.0, 48e-6)
    >>> d.factor, round(d.bayes_factor)
    (1000.0, 100)
    >>> force_scale_doubt(0.01, 60e3, 48e-3) is None  # as it should read
    True
    >>> force_scale_doubt(10e-6, 500.0, 100e-12) is None  # an AFM curve on a cell
    True
    """
    values = (scale, modulus, noise_pp)
    if not all(v is not None and math.isfinite(v) and v > 0 for v in values):
        return None
    noise = float(noise_pp)
    instruments = _instruments(scale)
    as_read = _log_mixture(instruments, noise, modulus)
    best, best_log = None, -math.inf
    for k, prior in UNIT_FACTORS.items():
        v = _log_mixture(instruments, k * noise, k * modulus) + math.log(prior)
        if v > best_log:
            best, best_log = k, v
    bf = math.exp(min(best_log - as_read, 700.0))
    if bf < BAYES_FACTOR:
        return None
    which = max(instruments, key=lambda i: i.log_density(best * noise, best * modulus))
    return ForceScaleDoubt(factor=float(best), bayes_factor=bf, instrument=which,
                           scale=float(scale), noise_pp=noise, modulus=float(modulus))


def _times(k: float) -> str:
    return f"{k:,.0f} times too small" if k > 1 else f"{1 / k:,.0f} times too large"


def force_scale_flag_text(doubt: ForceScaleDoubt, tip: str, *,
                          option: str = "--force-unit") -> str:
    """The ``force scale`` flag of a doubted force: one flag of a table's ``notes`` (no
    ``"; "`` outside its parentheses), whose words before the first parenthesis are what the
    console prints.

    ``tip``: the tip as the message names it (``"sphere R=10 mm"``); ``option``: what the user
    sets the force's unit with.
    """
    i, k = doubt.instrument, doubt.factor
    what = (f"E {format_pressure(doubt.modulus)} and a noise before contact of "
            f"{format_force(doubt.noise_pp)} peak-to-peak")
    typical = f"E ~{format_pressure(i.modulus)} and a noise of ~{format_force(i.noise_pp)}"
    slip = ("a force in N read as mN" if k == 1e3 else "a force in mN read as N"
            if k == 1e-3 else f"a force {_times(k)}")
    return (f"{FLAG_OPENING}: the force reads {_times(k)} for {i.name} tip, check {option} "
            f"({tip}, size {format_length(doubt.scale)}: {what} are "
            f"{doubt.bayes_factor:,.0f} times more typical of such an instrument multiplied by "
            f"{k:,g}, which reads {typical}; {slip} does this; so can an unusually soft or "
            "stiff specimen on an unusually quiet or noisy sensor: then ignore this)")


def force_scale_flag(tip, depth: float, modulus: float, noise_pp: float | None,
                     declared_pp: float | None = None) -> str | None:
    """The ``force scale`` flag of one palpation, or None: what ``fit``, ``fit --rheology``,
    ``map``, ``replay`` and ``follow`` each add to their flags.

    Parameters
    ----------
    tip
        The :class:`~palpbayes.contact.Tip` (its ``radius`` and ``describe()``).
    depth
        [m] The indentation depth (the tip's size when it has no radius).
    modulus
        [Pa] E as read (a rough value is enough).
    noise_pp
        [N] The peak-to-peak noise before contact (None: not measured).
    declared_pp
        [N] The sensor noise the user declared (``--noise-pp``), or None.  When given, the
        measured noise is set against it (:func:`palpbayes.sensor_noise.noise_scale_mismatch`) and
        the tip is not asked: the declared noise is the better reference.
    """
    if declared_pp is not None:
        ratio = None if noise_pp is None else noise_scale_mismatch(noise_pp, declared_pp)
        if ratio is None:
            return None
        how = f"{1 / ratio:,.0f} times below" if ratio < 1 else f"{ratio:,.0f} times above"
        return (f"{FLAG_OPENING}: the noise before contact is {how} the declared --noise-pp, "
                f"check --force-unit (the sensor noise: {format_force(noise_pp)} "
                f"peak-to-peak, 6 sd of the baseline, against {format_force(declared_pp)}; a "
                "force in N read as mN makes the force, and E, 1,000 times too small)")
    doubt = force_scale_doubt(tip_scale(tip.radius, depth), modulus, noise_pp)
    return None if doubt is None else force_scale_flag_text(doubt, tip.describe())
