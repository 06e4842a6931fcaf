"""A lump on the tip's axis in the specimen twin (palpbayes.twin.palpation.CentredLump)."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.contact import Tip
from palpbayes.errors import GeometryError
from palpbayes.inclusion import apparent_ratio, contact_radius, sensitivity
from palpbayes.twin.palpation import CentredLump, lump_ratio, solve_palpation

pytest.importorskip("skfem")

#: A paraboloid of unit radius 10 % into a block 2 high (unit length), coarse mesh.
TIP = Tip("paraboloid", radius=1.0)
BLOCK = {"radius": 4.0, "height": 2.0, "nu": 0.3, "base": "bonded"}
DEPTHS = np.array([0.1, 0.2])


def _ratio(lump: CentredLump) -> np.ndarray:
    return lump_ratio(BLOCK["radius"], BLOCK["height"], TIP, BLOCK["nu"], BLOCK["base"], DEPTHS,
                      lump, "coarse")


def test_a_lump_of_the_block_s_own_modulus_is_the_block():
    """The lump's nodes change the mesh, not the answer: ratio 1 against the plain mesh."""
    plain = solve_palpation(BLOCK["radius"], BLOCK["height"], TIP, BLOCK["nu"], BLOCK["base"],
                            DEPTHS, "coarse")
    same = solve_palpation(BLOCK["radius"], BLOCK["height"], TIP, BLOCK["nu"], BLOCK["base"],
                           DEPTHS, "coarse", CentredLump(0.5, 0.9, 1.0))
    np.testing.assert_allclose(same.shape, plain.shape, rtol=2e-3)


def test_stiff_and_soft_lumps_and_their_depth():
    """A stiff lump raises the force, a soft one lowers it, more with a larger contrast, and
    the same lump deeper down shows less."""
    def shape(ratio: float) -> np.ndarray:  # one mesh for the three lumps and their block
        return solve_palpation(BLOCK["radius"], BLOCK["height"], TIP, BLOCK["nu"],
                               BLOCK["base"], DEPTHS, "coarse",
                               CentredLump(0.5, 0.9, ratio)).shape

    block = shape(1.0)
    stiff, stiffer, soft = (shape(r) / block for r in (3.0, 10.0, 0.3))
    deeper = _ratio(CentredLump(0.5, 1.3, 10.0))
    assert np.all(soft < 1.0) and np.all(stiff > 1.0) and np.all(stiffer > stiff)
    assert np.all(1.0 < deeper) and np.all(deeper < stiffer)


def test_the_screening_model_is_a_lower_bound_for_a_stiff_lump():
    """The Reuss average of palpbayes.inclusion understates a stiff lump: the twin's ratio
    at the press depth lies above it (here by a factor of several in log excess)."""
    lump = CentredLump(0.5, 0.9, 10.0)
    fe = _ratio(lump)
    for d, r in zip(DEPTHS, fe, strict=True):
        V = sensitivity(0.0, radius=lump.radius, depth=lump.depth,
                        contact_radius=contact_radius(TIP, float(d)), thickness=2.0)
        screen = float(apparent_ratio(V, lump.ratio))
        print(f"press {d}: twin {r:.4f}, screening {screen:.4f}")
        assert 1.0 < screen and np.log(r) > 2.0 * np.log(screen), (d, r, screen)


def test_a_lump_that_does_not_fit_is_refused():
    with pytest.raises(GeometryError, match="at least one radius deep"):
        CentredLump(0.5, 0.4, 2.0)
    with pytest.raises(GeometryError, match="does not fit"):
        _ratio(CentredLump(0.5, 1.8, 2.0))
