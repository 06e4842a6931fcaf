"""Tests of palpbayes.kinematics: UR DH forward kinematics against hand-derived poses.

Notation: x0, y0, z0 are the base axes; T_i = Rot_z(q_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i).
Rot_x(+90°) maps (y, z) -> (z, -y): the new y axis is the old z, the new z axis is the old -y.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from propbudget import examples

from palpbayes.errors import InputError
from palpbayes.kinematics import (
    UR3E,
    UR5E,
    UR10E,
    DHParameters,
    dh_transform,
    forward_kinematics,
    tip_position,
    tip_z,
)

PI = np.pi
d1, d4, d5, d6 = 0.15185, 0.13105, 0.08535, 0.0921
a2, a3 = -0.24355, -0.2132

ZERO = np.zeros(6)
UPRIGHT = np.array([0.0, -PI / 2, 0.0, -PI / 2, 0.0, 0.0])
TOOL_DOWN = np.array([0.0, -PI / 2, PI / 2, -PI / 2, -PI / 2, 0.0])

TOL = 1e-9


def test_zero_pose_by_hand():
    """q = 0: every Rot_z is the identity, so only the d/a translations and alpha twists act.

    T1 = Trans_z(d1)·Rot_x(90°): origin (0, 0, d1); axes x1 = x0, y1 = z0, z1 = -y0.
    T2, T3 = Trans_x(a2), Trans_x(a3) along x1 = x0: origin (a2 + a3, 0, d1).
    T4 = Trans_z(d4)·Rot_x(90°): d4 along z3 = z1 = -y0 -> y = -d4; two 90° twists about x
         give x4 = x0, y4 = -y0, z4 = -z0.
    T5 = Trans_z(d5)·Rot_x(-90°): d5 along z4 = -z0 -> z = d1 - d5; Rot_x(-90°) makes the
         new y the old -z and the new z the old y: y5 = z0, z5 = y4 = -y0.
    T6 = Trans_z(d6): d6 along z5 = -y0 -> y = -(d4 + d6).
    Flange at (a2 + a3, -(d4 + d6), d1 - d5) = (-0.45675, -0.22315, 0.0665) with its z axis
    along -y0 (x6 = x0, y6 = z0, z6 = -y0).
    """
    T = forward_kinematics(ZERO)
    assert T.shape == (1, 4, 4)
    np.testing.assert_allclose(T[0, :3, 3], [-0.45675, -0.22315, 0.0665], atol=TOL)
    np.testing.assert_allclose(T[0, :3, 3], [a2 + a3, -(d4 + d6), d1 - d5], atol=TOL)
    R = np.column_stack([[1, 0, 0], [0, 0, 1], [0, -1, 0]])  # columns x6, y6, z6
    np.testing.assert_allclose(T[0, :3, :3], R, atol=TOL)
    np.testing.assert_allclose(T[0, 3], [0, 0, 0, 1], atol=0)


def test_upright_pose_by_hand():
    """q = (0, -90°, 0, -90°, 0, 0), the arm pointing straight up.

    After T1 (x1 = x0, y1 = z0, z1 = -y0), Rot_z(-90°) about z1 turns x into -y1 = -z0, y into
    x1 = x0.  So a2 and a3 act along -z0: the elbow and wrist 1 sit at z = d1 - a2 - a3 =
    0.6086.  Frame 3: x3 = -z0, y3 = x0, z3 = -y0.  Rot_z(-90°) about z3: x -> -y3 = -x0,
    y -> x3 = -z0; d4 along z3 -> y = -d4; Rot_x(90°): x4 = -x0, y4 = -y0, z4 = z0.
    d5 along z4 = +z0 -> z = d1 - a2 - a3 + d5; Rot_x(-90°): x5 = -x0, y5 = -z0, z5 = -y0.
    d6 along z5 -> y = -(d4 + d6).  Flange (0, -0.22315, 0.69395), axes x6 = -x0, y6 = -z0,
    z6 = -y0.
    """
    T = forward_kinematics(UPRIGHT)[0]
    np.testing.assert_allclose(T[:3, 3], [0.0, -(d4 + d6), d1 - a2 - a3 + d5], atol=TOL)
    np.testing.assert_allclose(T[:3, 3], [0.0, -0.22315, 0.69395], atol=TOL)
    R = np.column_stack([[-1, 0, 0], [0, 0, -1], [0, -1, 0]])
    np.testing.assert_allclose(T[:3, :3], R, atol=TOL)


def test_tool_down_pose_by_hand():
    """q = (0, -90°, 90°, -90°, -90°, 0), the usual palpation pose with the flange facing down.

    Frame 2 as in the upright pose (x2 = -z0, y2 = x0, z2 = -y0): a2 along -z0 -> z = d1 - a2.
    Rot_z(+90°) about z2: x3 = y2 = x0, y3 = -x2 = z0, so a3 acts along x0 -> x = a3.
    Rot_z(-90°) about z3 = -y0: x -> -y3 = -z0, y -> x3 = x0; d4 along -y0 -> y = -d4;
    Rot_x(90°): x4 = -z0, y4 = -y0, z4 = -x0.  Rot_z(-90°) about z4: x -> -y4 = y0,
    y -> x4 = -z0; d5 along z4 = -x0 -> x = a3 - d5; Rot_x(-90°): x5 = y0, y5 = x0,
    z5 = -z0.  d6 along -z0 -> z = d1 - a2 - d6.
    Flange (a3 - d5, -d4, d1 - a2 - d6) = (-0.29855, -0.13105, 0.3033), z6 = -z0 (down).
    """
    T = forward_kinematics(TOOL_DOWN)[0]
    np.testing.assert_allclose(T[:3, 3], [a3 - d5, -d4, d1 - a2 - d6], atol=TOL)
    np.testing.assert_allclose(T[:3, 3], [-0.29855, -0.13105, 0.3033], atol=TOL)
    R = np.column_stack([[0, 1, 0], [1, 0, 0], [0, 0, -1]])
    np.testing.assert_allclose(T[:3, :3], R, atol=TOL)


@pytest.mark.parametrize("theta", [PI / 2, -PI / 3, 1.0, PI])
def test_base_rotation_rotates_xy_about_z(theta):
    """Joint 1 pre-multiplies the chain by Rot_z(q0): x, y rotate, z is unchanged."""
    q = TOOL_DOWN.copy()
    q[0] = theta
    p = tip_position(q)[0]
    x, y, z = -0.29855, -0.13105, 0.3033
    c, s = np.cos(theta), np.sin(theta)
    np.testing.assert_allclose(p, [c * x - s * y, s * x + c * y, z], atol=TOL)


def test_last_joint_only_spins_about_flange_axis():
    """a6 = 0 and d6 lies on the joint-6 axis, so q5 leaves the flange origin in place."""
    q = np.tile(TOOL_DOWN, (4, 1))
    q[:, 5] = [0.0, 0.7, -2.0, PI]
    p = tip_position(q)
    np.testing.assert_allclose(p, np.tile([-0.29855, -0.13105, 0.3033], (4, 1)), atol=TOL)
    # ... and keeps the flange z axis (down).
    T = forward_kinematics(q)
    np.testing.assert_allclose(T[:, :3, 2], np.tile([0, 0, -1], (4, 1)), atol=TOL)


def test_tool_offset_along_flange_z():
    L = 0.0842  # sensor + tip [m]
    # Tool down: the tip is L below the flange.
    np.testing.assert_allclose(tip_z(TOOL_DOWN, tool_offset=L), [0.3033 - L], atol=TOL)
    np.testing.assert_allclose(tip_position(TOOL_DOWN, UR3E, L)[0, :2], [-0.29855, -0.13105],
                               atol=TOL)
    # Zero pose: the flange z axis is -y0, so the offset moves the tip along -y.
    np.testing.assert_allclose(tip_position(ZERO, tool_offset=L)[0],
                               [-0.45675, -0.22315 - L, 0.0665], atol=TOL)
    # A vector offset (0, 0, L) is the same as the scalar; x/y components follow x6, y6.
    np.testing.assert_allclose(forward_kinematics(TOOL_DOWN, tool_offset=[0, 0, L]),
                               forward_kinematics(TOOL_DOWN, tool_offset=L), atol=0)
    np.testing.assert_allclose(tip_position(TOOL_DOWN, tool_offset=[0.01, 0.02, 0.0])[0],
                               [-0.29855 + 0.02, -0.13105 + 0.01, 0.3033], atol=TOL)
    # The rotation is not changed by the offset.
    np.testing.assert_allclose(forward_kinematics(TOOL_DOWN, tool_offset=L)[0, :3, :3],
                               forward_kinematics(TOOL_DOWN)[0, :3, :3], atol=0)


@pytest.mark.parametrize("dh", [UR3E, UR5E, UR10E], ids=lambda dh: dh.name)
def test_zero_pose_other_robots(dh):
    x = dh.a[1] + dh.a[2]
    y = -(dh.d[3] + dh.d[5])
    z = dh.d[0] - dh.d[4]
    np.testing.assert_allclose(tip_position(ZERO, dh)[0], [x, y, z], atol=TOL)


def test_robot_tables():
    assert UR5E.d == (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996)
    assert UR5E.a == (0.0, -0.425, -0.3922, 0.0, 0.0, 0.0)
    assert UR10E.d == (0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655)
    assert UR10E.a == (0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0)
    assert UR3E.alpha == UR5E.alpha == UR10E.alpha == (PI / 2, 0.0, 0.0, PI / 2, -PI / 2, 0.0)
    with pytest.raises(AttributeError):
        UR3E.name = "x"  # frozen
    with pytest.raises(InputError, match="6 values"):
        DHParameters(d=(0.1,) * 5, a=(0.0,) * 6, alpha=(0.0,) * 6)


def test_batch_equals_per_sample():
    rng = np.random.default_rng(1)
    q = rng.uniform(-PI, PI, size=(50, 6))
    T = forward_kinematics(q, UR3E, 0.07)
    assert T.shape == (50, 4, 4)
    for i in range(q.shape[0]):
        np.testing.assert_allclose(T[i], forward_kinematics(q[i], UR3E, 0.07)[0], atol=1e-15)
    np.testing.assert_allclose(tip_z(q, UR3E, 0.07), T[:, 2, 3], atol=0)
    np.testing.assert_allclose(tip_position(q, UR3E, 0.07), T[:, :3, 3], atol=0)


def test_dh_transform_single_joint():
    T = dh_transform(np.array([PI / 2]), 0.1, 0.2, PI / 2)[0]
    # Rot_z(90°): x -> y0; a along it -> (0, a, d); Rot_x(90°) of the rotated frame.
    np.testing.assert_allclose(T[:3, 3], [0.0, 0.2, 0.1], atol=TOL)
    np.testing.assert_allclose(T[:3, :3], [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=TOL)


@pytest.mark.parametrize(
    "q, match",
    [
        (np.zeros(5), r"shape \(N, 6\)"),
        (np.zeros((3, 7)), r"shape \(N, 6\)"),
        (np.zeros((2, 3, 6)), r"shape \(N, 6\)"),
        (np.array([0, 0, np.nan, 0, 0, 0]), "non-finite"),
        (np.array([[0.0] * 6, [0, 0, 0, np.inf, 0, 0]]), "sample 1"),
        (["a"] * 6, "numeric"),
    ],
)
def test_bad_joint_angles(q, match):
    with pytest.raises(InputError, match=match):
        forward_kinematics(q)


@pytest.mark.parametrize("offset", [[0.0, 0.1], np.nan, [0.0, 0.0, np.inf]])
def test_bad_tool_offset(offset):
    with pytest.raises(InputError, match="tool_offset"):
        tip_z(ZERO, tool_offset=offset)


def test_input_error_is_value_error():
    with pytest.raises(ValueError):
        tip_z(np.zeros(4))


angles = arrays(np.float64, (8, 6), elements=st.floats(-2 * PI, 2 * PI, allow_nan=False))


@settings(max_examples=examples(60), deadline=None)
@given(q=angles, offset=st.floats(0.0, 0.3))
def test_rotation_is_proper_orthonormal(q, offset):
    T = forward_kinematics(q, UR3E, offset)
    R = T[:, :3, :3]
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    np.testing.assert_array_equal(T[:, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (8, 4)))


@settings(max_examples=examples(60), deadline=None)
@given(q=angles, theta=st.floats(-2 * PI, 2 * PI), offset=st.floats(0.0, 0.3))
def test_base_rotation_leaves_z_unchanged(q, theta, offset):
    q2 = q.copy()
    q2[:, 0] += theta
    p1 = tip_position(q, UR3E, offset)
    p2 = tip_position(q2, UR3E, offset)
    np.testing.assert_allclose(p2[:, 2], p1[:, 2], atol=1e-12)
    # ... and x, y turn by theta about z (radius preserved).
    np.testing.assert_allclose(np.hypot(p2[:, 0], p2[:, 1]), np.hypot(p1[:, 0], p1[:, 1]),
                               atol=1e-12)
