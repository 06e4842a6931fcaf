"""Map coordinates without floating-point residue (issue 46): the lattice inferred from a grid
that starts at 0 starts at 0.0, not at the circular mean's -2.7e-18 m, so map.csv, map.nc and
settings.json write 0 as 0."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.maps.lattice import Lattice, clean_coordinates, lattice_from_positions


def _grid(nx, ny, step, x0=0.0, y0=0.0):
    k = np.arange(nx * ny)
    return x0 + (k % nx) * step, y0 + (k // nx) * step


@pytest.mark.parametrize(("nx", "ny", "step"), [(4, 3, 2e-3), (9, 9, 3e-3), (15, 15, 3e-3),
                                                (4, 4, 5e-6)])
def test_a_grid_from_zero_gives_nodes_at_exactly_zero_and_whole_steps(nx, ny, step):
    lat, _ = lattice_from_positions(*_grid(nx, ny, step))
    assert (lat.x0, lat.y0, lat.step) == (0.0, 0.0, step)
    assert not np.signbit(lat.x0) and not np.signbit(lat.y0)
    want = [float(f"{i * step:.12g}") for i in range(nx)]  # the decimal numbers, as written
    assert lat.xs.tolist() == want and lat.node_x[:nx].tolist() == want
    assert lat.ys.tolist() == [float(f"{i * step:.12g}") for i in range(ny)]
    assert repr(float(lat.node_x[0])) == "0.0"


def test_an_offset_grid_keeps_its_decimal_positions():
    """A robot's grid in its own frame (from 123.4 mm, 2.5 mm steps): the nodes are the
    decimal positions, not 0.12590000000000001."""
    lat, node = lattice_from_positions(*_grid(5, 4, 2.5e-3, x0=0.1234, y0=-0.05))
    assert (lat.x0, lat.y0, lat.step) == (0.1234, -0.05, 0.0025)
    assert lat.xs.tolist() == [0.1234, 0.1259, 0.1284, 0.1309, 0.1334]
    np.testing.assert_array_equal(node, np.arange(20))


def test_node_coordinates_of_a_lattice_with_residue_are_clean():
    lat = Lattice(x0=-2.7e-18, y0=1e-19, step=0.0030000000000000005, nx=4, ny=2)
    assert lat.node_x.tolist() == [0.0, 0.003, 0.006, 0.009] * 2
    assert not np.signbit(lat.node_x).any() and lat.ys.tolist() == [0.0, 0.003]
    assert clean_coordinates(-4e-22, 5e-6) == 0.0 and not np.signbit(clean_coordinates(-4e-22,
                                                                                       5e-6))


def test_a_given_step_is_kept_as_given():
    x, y = _grid(4, 3, 2e-3)
    lat, _ = lattice_from_positions(x, y, step=0.0020000000000000005)
    assert lat.step == 0.0020000000000000005 and lat.x0 == 0.0
