"""Denavit–Hartenberg forward kinematics of Universal Robots arms (docs/design.md §2).

The tip height used by the contact models comes from the joint encoders, not from the robot's
own TCP estimate: each joint transform is built with the *standard* (distal) DH convention as
published by Universal Robots,

    T_i = Rot_z(theta_i) · Trans_z(d_i) · Trans_x(a_i) · Rot_x(alpha_i),

    T_flange = T_1 · T_2 · … · T_6,

with theta_i the joint angle q_i [rad] (UR's DH zero coincides with the controller's zero) and
(d_i, a_i, alpha_i) from UR's support article "DH parameters for calculations of kinematics and
dynamics" (universal-robots.com/articles/ur/application-installation/
dh-parameters-for-calculations-of-kinematics-and-dynamics/).  The resulting frame is the tool
flange (``tool0``); a sensor and tip mounted on it are a translation ``tool_offset`` in the flange
frame, along its z axis for an axial tool.

Everything is vectorised over samples: q has shape (N, 6) and the result (N, 4, 4), computed by
batched matrix products over the six joints (no Python loop over samples).

Example
-------
>>> import numpy as np
>>> from palpbayes.kinematics import UR3E, tip_position
>>> tip_position(np.zeros(6), UR3E).round(5)
array([[-0.45675, -0.22315,  0.0665 ]])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from math import pi

import numpy as np

from .errors import InputError

__all__ = [
    "DHParameters",
    "UR3E",
    "UR5E",
    "UR10E",
    "ROBOTS",
    "dh_transform",
    "forward_kinematics",
    "tip_position",
    "tip_z",
    "as_offset",
]


@dataclass(frozen=True)
class DHParameters:
    """Standard Denavit–Hartenberg table of a six-joint serial arm.

    Parameters
    ----------
    d
        [m] Link offsets d_1 … d_6 along the previous z axis.
    a
        [m] Link lengths a_1 … a_6 along the new x axis.
    alpha
        [rad] Link twists alpha_1 … alpha_6 about the new x axis.
    name
        Robot name, used in messages and metadata.

    Notes
    -----
    The joint angle theta_i is the measured joint position q_i; a constant joint offset is not
    part of the UR tables (their DH zero is the controller's zero).
    """

    d: tuple[float, ...]
    a: tuple[float, ...]
    alpha: tuple[float, ...]
    name: str = "robot"

    def __post_init__(self) -> None:
        for field_name in ("d", "a", "alpha"):
            values = tuple(float(v) for v in getattr(self, field_name))
            if len(values) != 6:
                raise InputError(
                    f"DH parameter {field_name!r} of {self.name!r} needs 6 values, "
                    f"got {len(values)}"
                )
            if not all(np.isfinite(values)):
                raise InputError(f"DH parameter {field_name!r} of {self.name!r} is not finite")
            object.__setattr__(self, field_name, values)


#: UR3e (UR support article "DH parameters for calculations of kinematics and dynamics").
UR3E = DHParameters(
    d=(0.15185, 0.0, 0.0, 0.13105, 0.08535, 0.0921),
    a=(0.0, -0.24355, -0.2132, 0.0, 0.0, 0.0),
    alpha=(pi / 2, 0.0, 0.0, pi / 2, -pi / 2, 0.0),
    name="UR3e",
)

#: UR5e (same source).
UR5E = DHParameters(
    d=(0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996),
    a=(0.0, -0.425, -0.3922, 0.0, 0.0, 0.0),
    alpha=(pi / 2, 0.0, 0.0, pi / 2, -pi / 2, 0.0),
    name="UR5e",
)

#: UR10e (same source).
UR10E = DHParameters(
    d=(0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655),
    a=(0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0),
    alpha=(pi / 2, 0.0, 0.0, pi / 2, -pi / 2, 0.0),
    name="UR10e",
)

#: Robots by lower-case name, for command-line options.
ROBOTS: dict[str, DHParameters] = {"ur3e": UR3E, "ur5e": UR5E, "ur10e": UR10E}


def _as_joint_array(q: np.ndarray | Sequence) -> np.ndarray:
    """Validate joint angles and return them as a float array of shape (N, 6)."""
    try:
        arr = np.asarray(q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"joint angles q must be numeric [rad] ({exc})") from None
    if arr.ndim == 1:
        arr = arr[np.newaxis, :]
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise InputError(
            f"joint angles q must have shape (N, 6) or (6,) [rad], got {np.shape(q)}"
        )
    bad = ~np.isfinite(arr)
    if bad.any():
        row = int(np.argmax(bad.any(axis=1)))
        raise InputError(
            f"joint angles q hold {int(bad.sum())} non-finite value(s) (NaN/inf), "
            f"first in sample {row}"
        )
    return arr


def as_offset(tool_offset: float | Sequence[float] | np.ndarray) -> np.ndarray:
    """Return the tool offset as a length-3 vector in the flange frame [m]."""
    off = np.asarray(tool_offset, dtype=float)
    if off.ndim == 0:
        off = np.array([0.0, 0.0, float(off)])
    if off.shape != (3,):
        raise InputError(
            "tool_offset must be a length along the flange z axis [m] or a length-3 vector "
            f"in the flange frame [m], got shape {off.shape}"
        )
    if not np.all(np.isfinite(off)):
        raise InputError(f"tool_offset {off.tolist()} is not finite")
    return off


def dh_transform(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """Homogeneous transforms of one joint, vectorised over samples.

    Parameters
    ----------
    theta
        [rad] Joint angles, shape (N,).
    d, a
        [m] Link offset and length.
    alpha
        [rad] Link twist.

    Returns
    -------
    ndarray
        Shape (N, 4, 4): Rot_z(theta) · Trans_z(d) · Trans_x(a) · Rot_x(alpha).
    """
    theta = np.asarray(theta, dtype=float)
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    T = np.zeros(theta.shape + (4, 4))
    T[..., 0, 0] = ct
    T[..., 0, 1] = -st * ca
    T[..., 0, 2] = st * sa
    T[..., 0, 3] = a * ct
    T[..., 1, 0] = st
    T[..., 1, 1] = ct * ca
    T[..., 1, 2] = -ct * sa
    T[..., 1, 3] = a * st
    T[..., 2, 1] = sa
    T[..., 2, 2] = ca
    T[..., 2, 3] = d
    T[..., 3, 3] = 1.0
    return T


def forward_kinematics(
    q: np.ndarray | Sequence,
    dh: DHParameters = UR3E,
    tool_offset: float | Sequence[float] | np.ndarray = 0.0,
) -> np.ndarray:
    """Pose of the tool tip in the robot base frame for each sample of joint angles.

    Parameters
    ----------
    q
        [rad] Joint angles, shape (N, 6) or (6,) (one sample).
    dh
        DH table of the arm (default :data:`UR3E`).
    tool_offset
        [m] Tip position in the flange frame: a scalar is a length along the flange z axis
        (force sensor + tip), a length-3 vector a general offset.  Default 0: the flange.

    Returns
    -------
    ndarray
        Shape (N, 4, 4): homogeneous transforms base ← tip; rotation block [-], translation
        [m].  A (6,) input gives N = 1.

    Raises
    ------
    InputError
        If q has the wrong shape or holds NaN/inf, or the offset is malformed.

    Notes
    -----
    Standard DH convention T_i = Rot_z(q_i) · Trans_z(d_i) · Trans_x(a_i) · Rot_x(alpha_i),
    T = T_1 ⋯ T_6 · Trans(tool_offset), with the parameters of UR's support article "DH
    parameters for calculations of kinematics and dynamics".
    """
    q = _as_joint_array(q)
    off = as_offset(tool_offset)
    T = dh_transform(q[:, 0], dh.d[0], dh.a[0], dh.alpha[0])
    for i in range(1, 6):
        T = T @ dh_transform(q[:, i], dh.d[i], dh.a[i], dh.alpha[i])
    if np.any(off != 0.0):
        T[:, :3, 3] += np.einsum("nij,j->ni", T[:, :3, :3], off)
    return T


def tip_position(
    q: np.ndarray | Sequence,
    dh: DHParameters = UR3E,
    tool_offset: float | Sequence[float] | np.ndarray = 0.0,
) -> np.ndarray:
    """[m] Tip position (x, y, z) in the base frame, shape (N, 3).

    See :func:`forward_kinematics` for the parameters.
    """
    return forward_kinematics(q, dh, tool_offset)[:, :3, 3]


def tip_z(
    q: np.ndarray | Sequence,
    dh: DHParameters = UR3E,
    tool_offset: float | Sequence[float] | np.ndarray = 0.0,
) -> np.ndarray:
    """[m] Tip height z in the base frame (up positive), shape (N,).

    See :func:`forward_kinematics` for the parameters.
    """
    return forward_kinematics(q, dh, tool_offset)[:, 2, 3]
