"""A solid at finite strain: a registered law with its natural parameters and, unless it is a
foam, its small-strain Poisson ratio — what a simulator presses and a fit reports.

>>> s = Solid.from_E0("neo-hookean", 60e3, nu=0.5)
>>> round(s.E0), s.params
(60000, {'mu': 20000.0})
>>> round(float(s.compression_stress(0.3)))  # P = mu (lambda - lambda^-2) at lambda 0.7
26816
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .registry import MaterialLaw, material_law
from .uniaxial import chord_modulus, compression_stress

__all__ = ["Solid"]


@dataclass(frozen=True)
class Solid:
    """A registered law with its natural parameters and Poisson ratio.

    Attributes
    ----------
    law
        The law's registry name.
    params
        Its natural parameters (moduli [Pa], exponents [-]).
    nu
        [-] The small-strain Poisson ratio of a law that is not a foam (None: 0.5,
        incompressible); a foam's is its parameter ``nu``.
    """

    law: str
    params: Mapping[str, float] = field(default_factory=dict)
    nu: float | None = None

    def __post_init__(self) -> None:
        law = material_law(self.law)
        object.__setattr__(self, "law", law.name)
        object.__setattr__(self, "params", {k: float(v) for k, v in self.params.items()})
        law.check(self.params)
        if self.nu is not None and not 0.0 <= float(self.nu) <= 0.5:
            raise InputError(f"Poisson ratio {self.nu!r} of a {law.title} solid: need 0..0.5")

    @classmethod
    def from_E0(cls, law: str, E0: float, shape: Mapping[str, float] | None = None,
                nu: float | None = None) -> Solid:
        """The solid of ``law`` whose small-strain modulus is ``E0`` [Pa], with its shape
        parameters (defaults: the law's typical values) and Poisson ratio ``nu`` (None: 0.5)."""
        spec = material_law(law)
        shape = {**spec.shape_defaults(), **(shape or {})}
        return cls(spec.name, spec.natural(float(E0), shape, 0.5 if nu is None else nu), nu)

    @property
    def spec(self) -> MaterialLaw:
        """The law's registry entry."""
        return material_law(self.law)

    @property
    def nu0(self) -> float:
        """[-] The small-strain Poisson ratio."""
        return self.spec.nu0(self.params, self.nu)

    @property
    def E0(self) -> float:
        """[Pa] The small-strain Young's modulus."""
        return self.spec.E0(self.params, self.nu)

    def compression_stress(self, strain) -> np.ndarray:
        """[Pa] Compressive nominal stress of free uniaxial compression at compressive
        engineering strains ``strain`` [-] (:func:`~palpbayes.material.compression_stress`)."""
        return compression_stress(self.spec, self.params, strain, self.nu)

    def chord(self, lo: float, hi: float) -> float:
        """[Pa] The chord modulus between compressive strains ``lo`` and ``hi``."""
        return chord_modulus(self.spec, self.params, lo, hi, self.nu)

    def describe(self) -> str:
        """The law and its parameters, e.g. ``'neo-Hookean mu=2e+04 Pa (nu 0.5)'``."""
        return f"{self.spec.describe(self.params)} (nu {self.nu0:g})"
