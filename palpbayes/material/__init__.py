"""Constitutive laws at finite strain: one registry of hyperelastic laws (neo-Hookean,
Mooney–Rivlin, Yeoh, Ogden, exponential, the Ogden–Hill foam), their small-strain E0 and nu0,
and uniaxial compression (:mod:`.uniaxial`).  ``"linear"`` (small-strain Hooke, the paper's
model) is a name, not a registered law: it has no finite strain.

A new law is one module that ends with ``LAW = register(MaterialLaw(...))``, imported here.
"""

from __future__ import annotations

from . import exponential, hyperfoam, mooney_rivlin, neo_hookean, ogden, yeoh  # noqa: F401
from .registry import (
    LINEAR,
    MaterialLaw,
    ShapeParameter,
    bulk_modulus,
    isochoric,
    lame_lambda,
    law_names,
    material_law,
    register,
    registered_laws,
)
from .solid import Solid
from .uniaxial import MAX_STRAIN, chord_modulus, compression_stress, lateral_stretch

__all__ = ["LINEAR", "MaterialLaw", "ShapeParameter", "bulk_modulus", "isochoric",
           "lame_lambda", "law_names", "material_law", "register", "registered_laws",
           "MAX_STRAIN", "chord_modulus", "compression_stress", "lateral_stretch", "Solid"]
