"""One press anywhere on a stiffness-map phantom: what an active search simulates.

:func:`palpbayes.sim.map.simulate_map` writes a raster of presses fixed in advance; an active
search (:mod:`palpbayes.active`) chooses each press after the last.  :class:`MapPhantom` is
the same phantom as an object that can be pressed at any (x, y): the smooth field E_app of
:func:`~palpbayes.inclusion.apparent_modulus`, each press's own material modulus
ln E = ln E_app + heterogeneity·N(0, 1), surface height, force offset and noise, drawn in the
order and by the code that ``simulate_map`` uses for its grid
(:func:`~palpbayes.sim.map.press_trace`): a press at a grid node with the node's random
stream is that node's trace.

A real specimen's heterogeneity is also spatially correlated: pressing beside a soft or stiff
patch does not average it away.  ``field_sd`` > 0 adds a stationary Gaussian random field
f(x, y) of ln E (Matérn, smoothness ``field_nu``, default 1 as the SPDE field of
:mod:`palpbayes.maps.spde`, correlation length ``field_length``: covariance
field_sd²·M_nu(sqrt(2 nu)·r / field_length), Rasmussen & Williams 2006, eq. 4.14), so a
press reads ln E = ln E_app + f(x, y) + heterogeneity·N(0, 1).  f is the field as the press
sees it (already averaged over the contact): its length should be at least about the contact
radius.  It is drawn once per phantom by random Fourier features (Rahimi & Recht 2007, NIPS):
f(x) = field_sd·sqrt(2/M)·Σ_j cos(w_j·x + u_j) with M = :data:`FIELD_FEATURES` frequencies
w_j from the Matérn spectral density (a bivariate Student t with 2 nu degrees of freedom,
scale 1/field_length) and phases u_j uniform, from the phantom's own stream
``child_seed(seed, "field")``.  Its covariance is exactly the Matérn one at every pair of
points, anywhere in the plane (no grid, no interpolation); its one-point law is a sum of M
independent bounded terms, Gaussian to within the central limit theorem (excess kurtosis
−1.5/M).  With ``field_sd`` = 0 (the default) no field is drawn and every press is as before.

A press may go to another depth than the phantom's (``press(..., depth=)``): the field E_app
is then the one under that depth's contact radius.  The screening model understates a stiff
lump several times against the finite-element twin (:mod:`palpbayes.inclusion`, "Limits");
``lump_gain`` scales the lump's log excess at each press depth,
ln E_app = gain(depth)·ln E_app,screening, so that the centre reads what the twin reads
(:func:`palpbayes.twin.palpation.pressed_ratio`; the profile's shape stays the screening
model's: the axisymmetric twin has no off-axis answer).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..contact import DEFAULT_NU, Tip
from ..errors import InputError
from ..inclusion import Inclusion, apparent_ratio, contact_radius, sensitivity
from ..paper import PAPER_TIPS
from ..sensor_noise import PAPER_NOISE_PP
from ..trace import IndentationTrace
from .campaign import child_seed
from .map import press_trace, read_map_truth

__all__ = ["FIELD_FEATURES", "MapPhantom"]

#: Random Fourier features of the correlated field (module docstring).
FIELD_FEATURES = 2048


@dataclass(frozen=True)
class MapPhantom:
    """A block of modulus ``E_background`` hiding ``inclusion`` (None: homogeneous).

    Parameters are those of :func:`palpbayes.sim.map.simulate_map` (SI units); ``depth``
    is the commanded indentation depth (default 10 % of ``thickness``).  ``field_sd`` (sd
    of ln E), ``field_length`` [m] and ``field_nu`` set the spatially correlated part of the
    heterogeneity (module docstring; off by default).  ``lump_gain``: pairs (press depth
    [m], gain) that scale the lump's log excess at each press depth (module docstring; empty:
    the screening model as it is).
    """

    E_background: float = 50e3
    inclusion: Inclusion | None = None
    tip: Tip = PAPER_TIPS["paraboloid"]
    thickness: float = 0.02
    depth: float | None = None
    nu: float = DEFAULT_NU
    heterogeneity: float = 0.03
    noise_pp: float = PAPER_NOISE_PP
    force_offset_sd: float = 5e-3
    z_surf: float = 0.1
    z_surf_halfwidth: float = 1e-3
    approach: float = 5e-4
    seed: int = 0
    field_sd: float = 0.0
    field_length: float = 5e-3
    field_nu: float = 1.0
    lump_gain: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        if not (self.E_background > 0 and self.thickness > 0):
            raise InputError("phantom: E_background [Pa] and thickness [m] must be > 0")
        inc = self.inclusion
        if inc is not None and inc.depth + inc.radius > self.thickness:
            raise InputError(f"phantom: the lump (centre depth {inc.depth:g} m + radius "
                             f"{inc.radius:g} m) reaches below the block ({self.thickness:g} m)")
        if not (math.isfinite(self.field_sd) and self.field_sd >= 0
                and self.field_length > 0 and self.field_nu > 0):
            raise InputError(f"phantom: field_sd {self.field_sd!r} must be >= 0 (sd of ln E), "
                             f"field_length {self.field_length!r} [m] and field_nu "
                             f"{self.field_nu!r} > 0")
        try:
            gains = tuple((float(d), float(g)) for d, g in self.lump_gain)
        except (TypeError, ValueError):
            gains = ((math.nan, math.nan),)
        if not all(math.isfinite(d) and d > 0 and math.isfinite(g) and g > 0 for d, g in gains):
            raise InputError(f"phantom: lump_gain {self.lump_gain!r} must be pairs (press "
                             "depth [m] > 0, gain > 0)")
        object.__setattr__(self, "lump_gain", gains)

    @property
    def indentation(self) -> float:
        """[m] The commanded indentation depth."""
        return 0.1 * self.thickness if self.depth is None else float(self.depth)

    @property
    def contact_radius(self) -> float:
        """[m] The tip's contact radius at the indentation depth."""
        return contact_radius(self.tip, self.indentation)

    def options(self) -> dict:
        """The per-press settings of :func:`press_trace`."""
        return {"nu": self.nu, "z_surf": self.z_surf, "z_surf_halfwidth": self.z_surf_halfwidth,
                "force_offset_sd": self.force_offset_sd, "heterogeneity": self.heterogeneity,
                "thickness": self.thickness, "depth": self.indentation,
                "approach": self.approach, "noise_pp": self.noise_pp}

    def gain(self, depth: float) -> float:
        """The lump's log-excess gain at press depth ``depth`` [m] (1 without ``lump_gain``).

        Raises InputError for a depth ``lump_gain`` does not hold."""
        if not self.lump_gain:
            return 1.0
        for d, g in self.lump_gain:
            if math.isclose(d, depth, rel_tol=1e-6):
                return float(g)
        raise InputError(f"phantom: no lump gain for press depth {depth:g} m (lump_gain holds "
                         f"{', '.join(f'{d:g}' for d, _ in self.lump_gain)} m)")

    def apparent_modulus(self, x, y, depth: float | None = None) -> np.ndarray:
        """[Pa] The smooth field E_app at (``x``, ``y``) [m] under a press to ``depth`` [m]
        (None: the phantom's)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if self.inclusion is None:
            return np.full(x.shape, float(self.E_background))
        d = self.indentation if depth is None else float(depth)
        inc = self.inclusion
        V = sensitivity(np.hypot(x - inc.x, y - inc.y), radius=inc.radius, depth=inc.depth,
                        contact_radius=contact_radius(self.tip, d), thickness=self.thickness)
        return self.E_background * apparent_ratio(V, inc.ratio) ** self.gain(d)

    @cached_property
    def _features(self) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (M, 2) [rad/m] and phases (M,) of the correlated field."""
        gen = np.random.default_rng(child_seed(self.seed, "field"))
        m, nu = FIELD_FEATURES, float(self.field_nu)
        z = gen.standard_normal((m, 2))
        scale = np.sqrt(2.0 * nu / gen.chisquare(2.0 * nu, m)) / self.field_length
        return z * scale[:, None], gen.uniform(0.0, 2.0 * math.pi, m)

    def background_field(self, x, y) -> np.ndarray:
        """The correlated field f (ln E) at (``x``, ``y``) [m]: 0 when ``field_sd`` is 0."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if self.field_sd == 0:
            return np.zeros(x.shape)
        w, u = self._features
        arg = x[..., None] * w[:, 0] + y[..., None] * w[:, 1] + u
        return self.field_sd * math.sqrt(2.0 / w.shape[0]) * np.cos(arg).sum(axis=-1)

    def press(self, x: float, y: float, key: int | str = 0,
              gen: np.random.Generator | None = None, depth: float | None = None
              ) -> IndentationTrace:
        """A simulated press at (``x``, ``y``) [m] to ``depth`` [m] (None: the phantom's);
        its random stream is ``child_seed(seed, "press", key)`` unless ``gen`` is given."""
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InputError(f"press position ({x!r}, {y!r}) must be finite [m]")
        if depth is not None and not (math.isfinite(depth) and 0 < depth < self.thickness):
            raise InputError(f"press depth {depth!r} must be > 0 and less than the block's "
                             f"thickness {self.thickness:g} [m]")
        gen = gen or np.random.default_rng(child_seed(self.seed, "press", key))
        E_app = float(self.apparent_modulus(x, y, depth))
        if self.field_sd:
            E_app *= math.exp(float(self.background_field(x, y)))
        opts = self.options() if depth is None else {**self.options(), "depth": float(depth)}
        return press_trace(E_app, gen, self.tip, opts, f"press-{key}")

    @classmethod
    def from_map(cls, folder: str | os.PathLike, **overrides) -> MapPhantom:
        """The phantom of a ``palpbayes simulate --map`` folder (its ``truth_lump.json``);
        settings the record does not hold (noise, offsets) take the defaults or
        ``overrides``."""
        from ..io.manifest import tip_from_row

        rec = read_map_truth(folder)
        inc = None
        if rec.get("has_lump"):
            inc = Inclusion(x=rec["x_m"], y=rec["y_m"], depth=rec["depth_m"],
                            radius=rec["radius_m"], ratio=rec["ratio"])
        tip_row = {"tip": rec["tip"], **{k[4:]: v for k, v in rec.items()
                                         if k.startswith("tip_") and v is not None}}
        import pandas as pd

        kw = {"E_background": rec["E_background_pa"], "inclusion": inc,
              "tip": tip_from_row(pd.Series(tip_row)), "thickness": rec["thickness_m"],
              "depth": rec["indentation_depth_m"], "nu": rec["nu"],
              "heterogeneity": rec["heterogeneity"]}
        return cls(**{**kw, **overrides})
