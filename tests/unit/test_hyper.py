"""The hyperelastic twin (palpbayes.twin.hyper*): its tangent against central differences of
its residual for every registered law, homogeneous compression against the closed form for
every law, small depths against the linear twin, every tip, the tables and their cache.

The default tests use coarse meshes (about 30 s together); the ``slow`` ones check the mesh
convergence, incompressibility at a table's resolution and the deep regime's trend.

Literature checks not pinned here, and why (docs/layout.md, the twin's row):

* Lin, Shreiber, Dimitriadis & Horkay 2009 (Biomech. Model. Mechanobiol. 8:345), their
  neo-Hookean and Mooney–Rivlin sphere-indentation forms, and the second-order solution of
  Du et al. 2022 (arXiv 2209.05646; J. Mech. Phys. Solids 2023): their formulas could not be
  read from any source reachable here (abstracts only), and none is written from memory.
* Shojaeifard & Bacca 2025 (Soft Matter; one-term Ogden): F = 16/9·E·sqrt(R)·D^1.5 for
  D << R (Hertz at nu = 0.5: 4/3·E/(1 − 1/4) = 16/9·E), pinned; their F ∝ D² for D >> R is
  not reproduced up to D = 2.4 R (:func:`test_deep_regime_shallow_limit_and_exponent`, slow).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from palpbayes.contact import Tip, get_law, register, unregister
from palpbayes.errors import FitError, GeometryError, InputError
from palpbayes.material import compression_stress, material_law, registered_laws
from palpbayes.twin import Specimen, solve_palpation
from palpbayes.twin.hyper import HyperSolid
from palpbayes.twin.hyper_compression import solve_hyper_compression
from palpbayes.twin.hyper_contact import tip_surface
from palpbayes.twin.hyper_newton import newton
from palpbayes.twin.hyper_palpation import fixed_dofs, solve_hyper_palpation
from palpbayes.twin.hyper_table import HyperTable, hyper_table

LAWS = [law.name for law in registered_laws()]
SPHERE = Tip("sphere", radius=1.0)


def _solid(name: str, nu: float) -> HyperSolid:
    law = material_law(name)
    return HyperSolid(np.linspace(0.0, 1.0, 4), np.linspace(0.0, 1.0, 4), law,
                      law.natural(1.0, law.shape_defaults(), nu), nu)


def _random_state(solid: HyperSolid, rng, amplitude: float = 0.03) -> np.ndarray:
    x = np.zeros(solid.size)
    x[:solid.n_u] = amplitude * rng.standard_normal(solid.n_u)
    ir = solid.dofs("r", lambda r, z: np.ones_like(r, dtype=bool))
    x[ir] *= solid.location(ir)[0]  # u_r vanishes on the axis
    if solid.mixed:
        x[solid.n_u:] = 0.05 * rng.standard_normal(solid.n_p)
    while solid.state(x) is None:
        x[:solid.n_u] *= 0.5
    return x


# ------------------------------------------------------------------------ the tangent
@pytest.mark.parametrize(("name", "nu"), [
    (n, nu) for n in LAWS for nu in (0.3, 0.5)
    if not (material_law(n).kind == "foam" and nu == 0.5)])  # a foam's nu is its own
def test_tangent_matches_central_differences(name, nu):
    """d(residual)/dx against central differences at a random finite strain (stretches
    0.7-1.4): relative error below 1e-7; the matrix symmetric."""
    solid = _solid(name, nu)
    rng = np.random.default_rng(3)
    x = _random_state(solid, rng)
    st = solid.state(x)
    k = solid.tangent(st)
    dx = rng.standard_normal(solid.size)
    h = 1e-7
    fd = (solid.residual(x + h * dx, solid.state(x + h * dx))
          - solid.residual(x - h * dx, solid.state(x - h * dx))) / (2 * h)
    assert np.linalg.norm(fd - k @ dx) <= 1e-7 * np.linalg.norm(k @ dx)
    kd = k.toarray()
    assert np.abs(kd - kd.T).max() <= 1e-12 * np.abs(kd).max()


@pytest.mark.parametrize("name", ["neo-hookean", "ogden", "hyperfoam"])
def test_tangent_at_equal_stretches(name):
    """The undeformed state (equal in-plane stretches everywhere: the limit of G_12) and a
    uniform dilatation: the tangent still matches the residual's central differences."""
    solid = _solid(name, 0.3)
    rng = np.random.default_rng(1)
    for scale in (0.0, 0.05):
        x = np.zeros(solid.size)
        ir = solid.dofs("r", lambda r, z: np.ones_like(r, dtype=bool))
        iz = solid.dofs("z", lambda r, z: np.ones_like(r, dtype=bool))
        x[ir], x[iz] = scale * solid.location(ir)[0], scale * solid.location(iz)[1]
        k = solid.tangent(solid.state(x))
        dx = rng.standard_normal(solid.size)
        h = 1e-7
        fd = (solid.residual(x + h * dx, solid.state(x + h * dx))
              - solid.residual(x - h * dx, solid.state(x - h * dx))) / (2 * h)
        assert np.linalg.norm(fd - k @ dx) <= 1e-7 * np.linalg.norm(k @ dx)


def test_small_strain_tangent_is_linear_elasticity():
    """At the undeformed state the tangent is the linear twin's matrix (E = 1, nu 0.3)."""
    from palpbayes.twin.fe import AxisymmetricSolid

    r, z = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 1.0, 3)
    hyper = HyperSolid(r, z, "neo-hookean", {"mu": 1.0 / 2.6}, 0.3)
    linear = AxisymmetricSolid(r, z, 0.3)
    kh = hyper.tangent(hyper.state(np.zeros(hyper.size))).toarray()
    # the linear twin's pressure is lambda·div u, the hyperelastic one's lambda·ln J: the
    # same at small strain
    assert np.allclose(kh, linear.matrix.toarray(), atol=1e-12)


# -------------------------------------------------------------------- compression
@pytest.mark.parametrize("name", LAWS)
def test_compression_between_lubricated_platens_is_the_closed_form(name):
    """Homogeneous uniaxial stress: the nominal stress of every law at 40 % strain equals
    :func:`palpbayes.material.compression_stress` to 1e-6 (nu 0.3 and, not a foam, 0.5)."""
    law = material_law(name)
    for nu in ((0.3,) if law.kind == "foam" else (0.3, 0.5)):
        p = law.natural(1.0, law.shape_defaults(), nu)
        got = solve_hyper_compression(1.0, 1.0, law, p, nu, "lubricated", np.array([0.4]))
        want = compression_stress(law, p, np.array([0.4]), nu)
        assert got.stress == pytest.approx(want, rel=1e-6)


def test_bonded_platens_stiffen_a_flat_block():
    """Bonded platens hold the faces: a wide block (radius 2.5 H) at nu 0.45 reads more
    than the lubricated closed form, and its side bulges."""
    p = material_law("neo-hookean").natural(1.0, {}, 0.45)
    got = solve_hyper_compression(1.0, 0.4, "neo-hookean", p, 0.45, "bonded",
                                  np.array([0.1, 0.2]))
    free = compression_stress("neo-hookean", p, np.array([0.1, 0.2]), 0.45)
    assert np.all(got.stress > 1.5 * free)
    assert np.all(np.diff(got.bulge) > 0)


# ------------------------------------------------------------------------- contact
def test_small_depth_matches_the_linear_twin():
    """Sphere, nu 0.45, bonded block 10 R × 10 R, coarse mesh, d/R 0.0025-0.01: the force
    is the linear twin's (solve_palpation) within 0.5 % at every depth, and within 0.3 %
    extrapolated to d = 0 (the finite-strain correction is linear in a/R ∝ sqrt(d))."""
    nu = 0.45
    p = material_law("neo-hookean").natural(1.0, {}, nu)
    d = np.array([0.0025, 0.005, 0.0075, 0.01])
    curve = solve_hyper_palpation(10.0, 10.0, SPHERE, "neo-hookean", p, nu, "bonded", d,
                                  "coarse")
    linear = solve_palpation(10.0, 10.0, SPHERE, nu, "bonded", d).shape / (1 - nu * nu)
    ratio = curve.force / linear
    assert np.all(np.abs(ratio - 1) < 0.005)
    assert abs(np.polyfit(np.sqrt(d), ratio, 1)[1] - 1) < 0.003
    assert np.all(curve.penetration < 1e-3 * d)


@pytest.mark.parametrize("tip", [Tip("flat", radius=0.5), SPHERE,
                                 Tip("paraboloid", radius=1.0),
                                 Tip("cone", half_angle=math.radians(70.0)),
                                 Tip("power", c=0.5, n=3.0)], ids=lambda t: t.kind)
def test_every_tip_presses_the_block(tip):
    """Every registered tip on a block (radius 2.8, height 2, free base), coarse mesh: the
    force rises with depth, within 5 % of the linear twin's at 1 % of the height, the
    penetration below 1e-3 of the depth."""
    p = material_law("neo-hookean").natural(1.0, {}, 0.3)
    d = np.array([0.02, 0.1])
    curve = solve_hyper_palpation(2.8, 2.0, tip, "neo-hookean", p, 0.3, "free", d, "coarse")
    linear = solve_palpation(2.8, 2.0, tip, 0.3, "free", d).shape / (1 - 0.09)
    assert np.all(np.diff(curve.force) > 0)
    assert curve.force[0] == pytest.approx(linear[0], rel=0.05)
    assert np.all(curve.penetration < 1e-3 * d)
    assert np.all(curve.contact_radius > 0)


def test_sphere_distance_is_exact_and_its_normal_radial():
    """The sphere's signed distance, normal (the centre's direction: 30° off vertical at
    r/R = 0.5) and Hessian."""
    surf = tip_surface(Tip("sphere", radius=2.0))
    r, z = np.array([1.0]), np.array([-math.sqrt(3.0)])  # on the sphere centred at (0, 0)
    g, n, hess = surf.distance(r, z, -2.0)
    assert g == pytest.approx([0.0], abs=1e-14)
    assert math.degrees(math.atan2(n[0, 0], -n[1, 0])) == pytest.approx(30.0)
    assert hess[:, :, 0] @ n[:, 0] == pytest.approx([0.0, 0.0], abs=1e-14)


@pytest.mark.parametrize("tip", [Tip("paraboloid", radius=1.5),
                                 Tip("cone", half_angle=math.radians(60.0)),
                                 Tip("power", c=0.7, n=2.5), Tip("flat", radius=1.0)],
                         ids=lambda t: t.kind)
def test_profile_distance_gradient_and_hessian(tip):
    """Signed distance of points near a profile: its gradient and Hessian against central
    differences of the distance itself."""
    surf = tip_surface(tip)
    r = np.array([0.3, 0.6, 0.8])
    z = np.array([0.05, 0.2, -0.05])
    g, n, hess = surf.distance(r, z, 0.0)
    h = 1e-6
    for i, (dr, dz) in enumerate(((h, 0.0), (0.0, h))):
        gp = surf.distance(r + dr, z + dz, 0.0)
        gm = surf.distance(r - dr, z - dz, 0.0)
        assert (gp[0] - gm[0]) / (2 * h) == pytest.approx(n[i], abs=1e-6)
        assert (gp[1] - gm[1]) / (2 * h) == pytest.approx(hess[:, i], abs=1e-4)


def test_a_tip_registered_elsewhere_is_pressed_with_no_edit_here():
    """A new tip kind is one file (its contact law with a profile): the twin takes the
    surface from the law's profile with numerical derivatives, here the paraboloid's profile
    under a new name against the analytic paraboloid surface."""
    law = register(dataclasses.replace(get_law("paraboloid"), kind="bowl", order=99))
    try:
        bowl = tip_surface(Tip("bowl", radius=1.5))
    finally:
        unregister(law.kind)
    exact = tip_surface(Tip("paraboloid", radius=1.5))
    r = np.array([0.1, 0.3, 0.6, 0.8])
    z = np.array([0.02, 0.05, 0.2, -0.05])
    for got, want in zip(bowl.distance(r, z, 0.0), exact.distance(r, z, 0.0), strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)


# ------------------------------------------------------------------------- errors
def test_errors_are_the_projects():
    p = material_law("neo-hookean").natural(1.0, {}, 0.3)
    with pytest.raises(GeometryError):
        solve_hyper_palpation(2.0, 1.0, SPHERE, "neo-hookean", p, 0.3, "glued",
                              np.array([0.1]), "coarse")
    with pytest.raises(GeometryError):
        solve_hyper_palpation(2.0, 1.0, SPHERE, "neo-hookean", p, 0.3, "free",
                              np.array([0.2, 0.1]), "coarse")
    with pytest.raises(GeometryError):
        solve_hyper_palpation(2.0, 1.0, Tip("flat", radius=3.0), "neo-hookean", p, 0.3,
                              "free", np.array([0.1]), "coarse")
    solid = _solid("neo-hookean", 0.3)
    fixed = fixed_dofs(solid, "bonded")
    top = solid.dofs("z", solid.on_top)
    with pytest.raises(FitError):  # one iteration cannot converge a 30 % compression
        newton(solid, np.zeros(solid.size), np.r_[fixed, top],
               np.r_[np.zeros(fixed.size), np.full(top.size, -0.3)], max_iter=1)


# -------------------------------------------------------------------------- tables
def test_table_interpolation_is_monotone_and_scales_with_E0():
    """A synthetic table: F linear in E0, 0 at d <= 0, monotone between nodes and depths,
    the nodes' curves reproduced, NaN outside the shape grid or from a failed node."""
    depth = np.geomspace(0.01, 0.3, 8)
    base = depth ** 1.5
    values = np.stack([base, 1.2 * base ** 1.05, 1.5 * base ** 1.1])
    table = HyperTable("exponential", 0.3, "free", 0.01, False, ("b",),
                       (np.array([0.0, 0.5, 1.0]),), depth, values)
    d = np.linspace(-0.001, 0.004, 200)
    f1 = table.force(d, 1.0, {"b": 0.25})
    assert np.all(f1[d <= 0] == 0) and np.all(np.diff(f1[d > 0]) > 0)
    assert table.force(d, 2.0, {"b": 0.25}) == pytest.approx(2 * f1)
    node = table.force(depth * 0.01, 3.0, {"b": 0.5})
    assert node == pytest.approx(3.0 * 1.2 * base ** 1.05 * 1e-4, rel=1e-12)
    assert np.isnan(table.force(np.array([0.001]), 1.0, {"b": 2.0})).all()
    bad = HyperTable("exponential", 0.3, "free", 0.01, False, ("b",),
                     (np.array([0.0, 1.0]),), depth, np.stack([base, np.nan * base]))
    assert np.isnan(bad.force(np.array([0.001]), 1.0, {"b": 0.5})).all()


def test_table_built_cached_and_read(tmp_path, monkeypatch):
    """A neo-Hookean table of a small block (coarse mesh): solved once, read back from the
    disk cache identical; the force within 6 % of the linear twin's at d/R 0.1-0.2 (at
    nu 0.3 finite strain adds ~9 %·a/R)."""
    monkeypatch.setenv("PALPBAYES_CACHE_DIR", str(tmp_path))
    spec = Specimen(0.02, diameter=0.056)
    tip = Tip("sphere", radius=0.01)
    first = hyper_table("neo-hookean", spec, tip, 0.3, "free", max_depth=0.002,
                        resolution="coarse")
    assert list(tmp_path.rglob("hyper-curve-*.npz"))
    again = hyper_table("neo-hookean", spec, tip, 0.3, "free", max_depth=0.002,
                        resolution="coarse")
    assert np.array_equal(first.values, again.values) and not first.notes
    f = first.force(np.array([0.001, 0.002]), 60e3)
    linear = solve_palpation(2.8, 2.0, SPHERE, 0.3, "free", np.array([0.1, 0.2])).shape
    assert f == pytest.approx(60e3 / (1 - 0.09) * 1e-4 * linear, rel=0.06)
    assert f[1] / f[0] > linear[1] / linear[0]  # finite strain stiffens it: ~9 %·a/R
    with pytest.raises(InputError):
        hyper_table("neo-hookean", spec, tip, 0.3, "free", {"alpha": [1.0]})


# ------------------------------------------------------------------------- slow checks
@pytest.mark.slow
def test_mesh_convergence_default_against_fine():
    """The issue's block (equal-area cylinder of 50 × 50 × 20 mm, in units of the 10 mm
    sphere: radius 2.82, height 2), nu 0.3, free base: default and fine meshes within 0.5 %
    at d/R 0.1-0.3."""
    p = material_law("neo-hookean").natural(1.0, {}, 0.3)
    d = np.array([0.1, 0.2, 0.3])
    default = solve_hyper_palpation(2.821, 2.0, SPHERE, "neo-hookean", p, 0.3, "free", d)
    fine = solve_hyper_palpation(2.821, 2.0, SPHERE, "neo-hookean", p, 0.3, "free", d, "fine")
    assert default.force == pytest.approx(fine.force, rel=0.005)


@pytest.mark.slow
def test_incompressible_small_depth_default_mesh():
    """nu = 0.5 (the constraint ln J = 0), default mesh: the small-depth force extrapolated
    to d = 0 is the linear twin's within 0.3 %, and the raw ratio within 1 %."""
    p = material_law("neo-hookean").natural(1.0, {}, 0.5)
    d = np.array([0.0025, 0.005, 0.0075, 0.01])
    curve = solve_hyper_palpation(10.0, 10.0, SPHERE, "neo-hookean", p, 0.5, "bonded", d)
    linear = solve_palpation(10.0, 10.0, SPHERE, 0.5, "bonded", d).shape / 0.75
    ratio = curve.force / linear
    assert np.all(np.abs(ratio - 1) < 0.01)
    assert abs(np.polyfit(np.sqrt(d), ratio, 1)[1] - 1) < 0.003


@pytest.mark.slow
def test_deep_regime_shallow_limit_and_exponent():
    """Shojaeifard & Bacca 2025: one-term Ogden (alpha 2.5), incompressible, a sphere on its
    stem into a block 30 R × 30 R (coarse mesh).  Their Hertzian regime, F = 16/9·E·sqrt(R)·
    D^1.5 for D << R: within 2 % at D = 0.04 R, local exponent d ln F/d ln D 1.5 ± 0.03.

    Their parabolic regime (F ∝ D² for D >> R) is NOT reproduced here: the local exponent
    falls from 1.49 (D 0.05 R) to 1.42 (0.3 R), 1.30 (1.1 R), 1.11 (1.7 R) and 1.06 (2.4 R),
    as a frictionless punch's would once the contact reaches the sphere's equator, and the
    coarse mesh stops converging near D = 2.8 R (benchmarks/bench_finite_twin.py, part deep):
    pinned here as the fall below 1.5 past D = R, so that a change is noticed."""
    law = material_law("ogden")
    p = law.natural(1.0, {"alpha_1": 2.5}, 0.5)
    d = np.array([0.04, 0.06, 0.3, 0.35, 1.0, 1.15])
    curve = solve_hyper_palpation(30.0, 30.0, SPHERE, law, p, 0.5, "bonded", d, "coarse")
    slope = np.diff(np.log(curve.force))[::2] / np.diff(np.log(d))[::2]
    assert curve.force[0] == pytest.approx(16 / 9 * 0.04 ** 1.5, rel=0.02)
    assert slope[0] == pytest.approx(1.5, abs=0.03)
    assert slope[-1] < slope[0] - 0.1
