"""One press anywhere on a stiffness-map phantom: what an active search simulates.

:func:`palpbayes.sim.map.simulate_map` writes a raster of presses fixed in advance; an active
search (:mod:`palpbayes.active`) chooses each press after the last.  :class:`MapPhantom` is
the same phantom as an object that can be pressed at any (x, y): the smooth field E_app of
:func:`~palpbayes.inclusion.apparent_modulus`, each press's own material modulus
ln E = ln E_app + heterogeneity·N(0, 1), surface height, force offset and noise, drawn in the
order and by the code that ``simulate_map`` uses for its grid
(:func:`~palpbayes.sim.map.press_trace`): a press at a grid node with the node's random
stream is that node's trace.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..contact import DEFAULT_NU, Tip
from ..errors import InputError
from ..inclusion import Inclusion, apparent_ratio, contact_radius, sensitivity
from ..paper import PAPER_TIPS
from ..sensor_noise import PAPER_NOISE_PP
from ..trace import IndentationTrace
from .campaign import child_seed
from .map import press_trace, read_map_truth

__all__ = ["MapPhantom"]


@dataclass(frozen=True)
class MapPhantom:
    """A block of modulus ``E_background`` hiding ``inclusion`` (None: homogeneous).

    Parameters are those of :func:`palpbayes.sim.map.simulate_map` (SI units); ``depth``
    is the commanded indentation depth (default 10 % of ``thickness``).
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

    def __post_init__(self) -> None:
        if not (self.E_background > 0 and self.thickness > 0):
            raise InputError("phantom: E_background [Pa] and thickness [m] must be > 0")
        inc = self.inclusion
        if inc is not None and inc.depth + inc.radius > self.thickness:
            raise InputError(f"phantom: the lump (centre depth {inc.depth:g} m + radius "
                             f"{inc.radius:g} m) reaches below the block ({self.thickness:g} m)")

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

    def apparent_modulus(self, x, y) -> np.ndarray:
        """[Pa] The smooth field E_app at (``x``, ``y``) [m]."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if self.inclusion is None:
            return np.full(x.shape, float(self.E_background))
        inc = self.inclusion
        V = sensitivity(np.hypot(x - inc.x, y - inc.y), radius=inc.radius, depth=inc.depth,
                        contact_radius=self.contact_radius, thickness=self.thickness)
        return self.E_background * apparent_ratio(V, inc.ratio)

    def press(self, x: float, y: float, key: int | str = 0,
              gen: np.random.Generator | None = None) -> IndentationTrace:
        """A simulated press at (``x``, ``y``) [m]; its random stream is
        ``child_seed(seed, "press", key)`` unless ``gen`` is given."""
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InputError(f"press position ({x!r}, {y!r}) must be finite [m]")
        gen = gen or np.random.default_rng(child_seed(self.seed, "press", key))
        E_app = float(self.apparent_modulus(x, y))
        return press_trace(E_app, gen, self.tip, self.options(), f"press-{key}")

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
