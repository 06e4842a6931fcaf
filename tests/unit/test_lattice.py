"""The palpation lattice: inference from positions, Laplacian and its closed-form spectrum, pad."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.errors import InputError
from palpbayes.maps import Lattice, laplacian, laplacian_eigenvalues, lattice_from_positions, pad

STEP = 0.004  # 4 mm


def _grid(nx=7, ny=5, x0=0.012, y0=-0.03, step=STEP):
    lat = Lattice(x0, y0, step, nx, ny)
    return lat, lat.node_x, lat.node_y


def test_lattice_nodes_are_row_major():
    lat, x, y = _grid()
    assert lat.n_nodes == 35 and x.size == y.size == 35
    assert lat.index(3, 2) == 2 * 7 + 3
    assert x[lat.index(3, 2)] == pytest.approx(0.012 + 3 * STEP)
    assert y[lat.index(3, 2)] == pytest.approx(-0.03 + 2 * STEP)
    np.testing.assert_array_equal(lat.index(np.array([0, 6]), np.array([4, 4])), [28, 34])
    with pytest.raises(InputError):
        lat.index(7, 0)
    with pytest.raises(InputError):
        Lattice(0.0, 0.0, 0.0, 3, 3)


def test_shuffled_full_grid_recovers_lattice_and_nodes():
    lat, x, y = _grid()
    order = np.random.default_rng(0).permutation(x.size)
    got, node = lattice_from_positions(x[order], y[order])
    assert (got.nx, got.ny) == (7, 5)
    assert got.step == pytest.approx(STEP, rel=1e-9)
    assert (got.x0, got.y0) == pytest.approx((0.012, -0.03), abs=1e-12)
    np.testing.assert_array_equal(node, order)


def test_missing_nodes_repeats_and_jitter_within_tol():
    lat, x, y = _grid(nx=12, ny=9)
    rng = np.random.default_rng(1)
    keep = rng.random(x.size) > 0.3
    keep[[0, lat.n_nodes - 1]] = True  # keep the extent
    idx = np.concatenate([np.flatnonzero(keep), [lat.index(4, 4)] * 3])  # a node seen 4 times
    xj = x[idx] + rng.uniform(-0.15, 0.15, idx.size) * STEP
    yj = y[idx] + rng.uniform(-0.15, 0.15, idx.size) * STEP
    got, node = lattice_from_positions(xj, yj)
    assert (got.nx, got.ny) == (12, 9)
    assert got.step == pytest.approx(STEP, rel=0.01)
    np.testing.assert_array_equal(node, idx)
    # a given step is used as is
    got2, node2 = lattice_from_positions(xj, yj, step=STEP)
    assert got2.step == STEP
    np.testing.assert_array_equal(node2, idx)


def test_coarser_axis_on_the_finer_step_and_common_divisor():
    xx, yy = np.meshgrid(np.arange(5) * 2 * STEP, np.arange(4) * STEP)  # x every 2 steps
    got, node = lattice_from_positions(xx.ravel(), yy.ravel())
    assert (got.nx, got.ny, got.step) == (9, 4, pytest.approx(STEP))
    assert np.all(node % 9 % 2 == 0)  # odd columns carry no data
    xx, yy = np.meshgrid(np.arange(5) * 1.5 * STEP, np.arange(4) * STEP)
    with pytest.raises(InputError, match="step="):
        lattice_from_positions(xx.ravel(), yy.ravel())
    got, _ = lattice_from_positions(xx.ravel(), yy.ravel(), step=0.5 * STEP)
    assert (got.nx, got.ny) == (13, 7)


def test_position_errors_name_the_offending_value():
    lat, x, y = _grid()
    x = x.copy()
    x[5] += 0.4 * STEP
    with pytest.raises(InputError, match=r"position 5 .*0\.4\d steps off"):
        lattice_from_positions(x, y)
    x[5] = np.nan
    with pytest.raises(InputError, match="position 5"):
        lattice_from_positions(x, y)
    with pytest.raises(InputError, match="2-D grid"):  # a line scan
        lattice_from_positions(np.arange(6) * STEP, np.zeros(6))
    with pytest.raises(InputError, match="distinct positions"):
        lattice_from_positions([0.0, 0.0], [1.0, 1.0])
    with pytest.raises(InputError, match="same length"):
        lattice_from_positions([0.0, 1.0], [1.0])
    with pytest.raises(InputError, match="step"):
        lattice_from_positions(lat.node_x, lat.node_y, step=-1.0)
    with pytest.raises(InputError, match="outlying|nodes"):
        lattice_from_positions(np.r_[lat.node_x, 1e3 + lat.x0], np.r_[y, y[0]], step=STEP)


def test_laplacian_is_neumann_and_has_dct_spectrum():
    L = laplacian(6, 4)
    assert L.shape == (24, 24)
    assert abs(L - L.T).max() == 0
    np.testing.assert_allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0)
    lat = Lattice(0, 0, 1, 6, 4)
    assert L[lat.index(0, 0), lat.index(0, 0)] == 2  # corner: two neighbours
    assert L[lat.index(2, 0), lat.index(2, 0)] == 3
    assert L[lat.index(2, 2), lat.index(2, 2)] == 4
    assert L[lat.index(2, 2), lat.index(2, 3)] == -1
    np.testing.assert_allclose(np.sort(laplacian_eigenvalues(6, 4).ravel()),
                               np.linalg.eigvalsh(L.toarray()), atol=1e-12)


def test_pad_maps_every_data_node_to_its_place():
    lat, x, y = _grid()
    p, index = pad(lat, 3)
    assert (p.nx, p.ny, p.step) == (13, 11, STEP)
    np.testing.assert_allclose(p.node_x[index], x, atol=1e-15)
    np.testing.assert_allclose(p.node_y[index], y, atol=1e-15)
    assert pad(lat, 0)[0] == lat
    with pytest.raises(InputError):
        pad(lat, -1)


def test_a_line_scan_is_a_lattice_of_one_row_or_column_only_when_asked():
    x = 3.0 + np.arange(6) * STEP
    lat, node = lattice_from_positions(x, np.full(6, 2.0), line=True)
    assert (lat.nx, lat.ny) == (6, 1) and lat.step == pytest.approx(STEP)
    np.testing.assert_array_equal(node, np.arange(6))
    lat, node = lattice_from_positions(np.full(6, 2.0), x[::-1], line=True)
    assert (lat.nx, lat.ny) == (1, 6)
    np.testing.assert_array_equal(node, np.arange(6)[::-1])
    with pytest.raises(InputError, match="single y value"):
        lattice_from_positions(x, np.full(6, 2.0))
