"""Newton's method and adaptive load steps for the hyperelastic twin (:mod:`.hyper`).

:func:`newton` solves one equilibrium: a full Newton step (the consistent tangent, one SuperLU
factorization of the free block per iteration, in its symmetric mode as the linear twin's),
halved while it leads to an inadmissible state (J <= 0), converged when the free residual is
at most ``rtol`` of the internal forces and the last displacement increment at most ``utol``
of the problem's length (or, at round-off, when the residual stops falling below
:data:`STAGNANT` of them with increments 1,000 times smaller).  :func:`march` follows a
load path in steps that are halved on failure and grown after easy ones, with an augmented
Lagrangian's updates between them.  A solve that cannot converge raises
:class:`~palpbayes.errors.FitError`, naming the load it reached.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import FitError
from .hyper import HyperSolid

__all__ = ["NewtonResult", "newton", "march", "STAGNANT"]

#: A residual that stops falling below this fraction of the internal forces, with increments
#: 1,000 times below the displacement tolerance, is round-off: converged.
STAGNANT = 1e-4


@dataclass
class NewtonResult:
    """A converged Newton solve.

    Attributes
    ----------
    x
        The unknowns.
    residual
        The full residual at ``x`` (reactions at prescribed and contact-loaded dofs).
    iterations
        Newton iterations taken.
    """

    x: np.ndarray
    residual: np.ndarray
    iterations: int


def _factor(k: sp.csr_matrix, free: np.ndarray):
    block = k[free][:, free].tocsc()
    try:
        return spla.splu(block, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options={"SymmetricMode": True})
    except RuntimeError:
        return spla.splu(block)


def newton(solid: HyperSolid, x0: np.ndarray, fixed: np.ndarray, values: np.ndarray,
           extra: Callable[[np.ndarray, int], tuple[np.ndarray, sp.spmatrix]] | None = None,
           rtol: float = 1e-8, utol: float = 1e-6, max_iter: int = 30,
           length: float = 1.0) -> NewtonResult:
    """Equilibrium of ``solid`` from ``x0`` with ``x[fixed] = values``.

    Parameters
    ----------
    extra
        ``extra(x, iteration) -> (residual, tangent)`` of further forces (the contact
        penalty), added to the solid's.
    rtol
        Convergence when the free residual's norm is at most ``rtol`` times the internal
        forces' (all displacement dofs) ...
    utol
        ... and the last displacement increment at most ``utol``·``length``.
    max_iter
        Iterations before :class:`~palpbayes.errors.FitError`.

    Raises
    ------
    FitError
        No convergence, or no admissible state along the Newton direction.
    """
    x = np.array(x0, dtype=float)
    x[fixed] = values
    free = np.setdiff1d(np.arange(solid.size), fixed)
    free_u = free[free < solid.n_u]
    st = solid.state(x)
    if st is None:
        raise FitError("the starting state of a Newton solve is inadmissible (J <= 0)")
    step_u = np.inf
    last = np.inf
    for it in range(max_iter):
        r = solid.residual(x, st)
        k = solid.tangent(st)
        if extra is not None:
            r_c, k_c = extra(x, it)
            r = r + r_c
            k = k + k_c
        scale = max(np.linalg.norm(r[:solid.n_u]), 1e-300)
        rnorm = np.linalg.norm(r[free_u])
        if rnorm <= rtol * scale and step_u <= utol * length:
            return NewtonResult(x, r, it)
        if (rnorm <= STAGNANT * scale and rnorm > 0.5 * last
                and step_u <= 1e-3 * utol * length):
            # round-off: the residual stopped falling with increments far below utol (a
            # first, tiny load step on a large body, where the internal forces are small)
            return NewtonResult(x, r, it)
        last = rnorm
        if not np.all(np.isfinite(r)):
            break
        dx = np.zeros_like(x)
        dx[free] = -_factor(k, free).solve(r[free])
        alpha = 1.0
        for _ in range(12):
            trial = x + alpha * dx
            st_trial = solid.state(trial)
            if st_trial is not None:
                break
            alpha *= 0.5
        else:
            raise FitError("no admissible state along the Newton direction (J <= 0)")
        x, st = trial, st_trial
        step_u = alpha * np.max(np.abs(dx[:solid.n_u]))
    raise FitError(f"Newton's method did not converge in {max_iter} iterations "
                   f"(residual {rnorm:.3g} of {scale:.3g})")


# Many parameters: a load-stepping Newton solve: the solid, targets, constraints, callbacks and the
# solver's controls.
def march(solid: HyperSolid, targets: np.ndarray, fixed: np.ndarray,
          load: Callable[[float], tuple[np.ndarray, Callable | None]],
          record: Callable[[int, np.ndarray, NewtonResult], None], what: str,
          max_cuts: int = 10, max_iter: int = 25, contact=None,
          augmentations: int = 8, first_fraction: float = 1.0) -> tuple[int, int]:
    """Load ``solid`` along the increasing load parameters ``targets`` (from 0), in adaptive
    steps: each target is reached by one or more steps, a step halved when Newton's method
    fails (up to ``max_cuts`` times) and grown by half after an easy one (<= 8 iterations),
    the predictor extrapolating the last two solutions.

    Parameters
    ----------
    load
        ``load(t) -> (values of the fixed dofs, extra forces or None)`` at load ``t``
        (``extra`` as :func:`newton`'s).
    record
        ``record(i, x, result)`` at each target i.
    contact
        An object with ``augment(x, t) -> bool`` (an augmented Lagrangian's update after a
        converged step: True to solve the step again, up to ``augmentations`` times) and an
        array attribute ``multiplier`` (restored when a step is cut), or None.
    first_fraction
        The first step is ``targets[0]/first_fraction``.
    what
        The solve's name in the error's message.

    Returns
    -------
    (steps, iterations)

    Raises
    ------
    FitError
        A step could not be made to converge: the message names the load reached.
    """
    x = np.zeros(solid.size)
    x_old, t_old, t = None, 0.0, 0.0
    step = float(targets[0]) / first_fraction
    steps = iters = 0
    for i, target in enumerate(targets):
        while t < target * (1.0 - 1e-12):
            dt = min(step, target - t)
            values, extra = load(t + dt)
            start = x if x_old is None else x + (x - x_old) * (dt / (t - t_old))
            if solid.state(start) is None:
                start = x
            saved = None if contact is None else contact.multiplier.copy()
            try:
                sol = newton(solid, start, fixed, values, extra=extra, length=float(target),
                             max_iter=max_iter)
                for _ in range(augmentations if contact is not None else 0):
                    if not contact.augment(sol.x, t + dt):
                        break
                    more = newton(solid, sol.x, fixed, values, extra=extra,
                                  length=float(target), max_iter=max_iter)
                    sol = NewtonResult(more.x, more.residual, sol.iterations + more.iterations)
            except FitError as err:
                if saved is not None:
                    contact.multiplier = saved
                step = dt / 2
                if step < target * 0.5 ** max_cuts:
                    raise FitError(f"{what} did not converge beyond {t:.4g} (asked "
                                   f"{target:.4g}): {err}") from None
                continue
            x_old, t_old, x, t = x, t, sol.x, t + dt
            steps += 1
            iters += sol.iterations
            step = dt * (1.5 if sol.iterations <= 8 else 1.0)
        record(i, x, sol)
    return steps, iters
