"""The constitutive-law registry (palpbayes.material, issue 56 item 1): every law's small-strain
modulus is the slope of its compression curve, its tangent is the derivative of its stresses,
and its uniaxial compression matches the closed forms of docs/design.md §14."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.errors import InputError
from palpbayes.material import (
    LINEAR,
    chord_modulus,
    compression_stress,
    lateral_stretch,
    law_names,
    material_law,
    registered_laws,
)

LAWS = [law.name for law in registered_laws()]
E0 = 60e3


def _params(name, nu):
    law = material_law(name)
    return law, law.natural(E0, law.shape_defaults(), nu)


def test_the_registry_names_every_law_the_issue_asks_for():
    names = law_names()
    assert names[0] == LINEAR
    for n in ("neo-hookean", "mooney-rivlin", "yeoh", "yeoh-2", "ogden", "ogden-2", "ogden-3",
              "exponential", "hyperfoam", "hyperfoam-2"):
        assert n in names
    assert material_law("Neo_Hookean").name == "neo-hookean"
    with pytest.raises(InputError, match="unknown material law 'gent'.*neo-hookean"):
        material_law("gent")
    for law in registered_laws():
        assert law.reference and law.energy and law.parameters
        assert all(unit in ("Pa", "-") for _, unit in law.parameters)


@pytest.mark.parametrize("name", LAWS)
@pytest.mark.parametrize("nu", [0.5, 0.3, 0.0])
def test_E0_is_the_initial_slope_of_compression(name, nu):
    law, p = _params(name, nu)
    nu0 = law.nu0(p, nu)
    assert law.E0(p, nu) == pytest.approx(E0, rel=1e-12)
    assert 2 * law.mu0(p) * (1 + nu0) == pytest.approx(E0, rel=1e-12)
    h = 1e-6  # a one-sided difference: its error is the curvature times h/2
    slope = compression_stress(law, p, h, nu) / h
    assert slope == pytest.approx(E0, rel=1e-5)
    assert chord_modulus(law, p, 0.0, 0.0, nu) == pytest.approx(E0, rel=1e-5)


@pytest.mark.parametrize("name", LAWS)
def test_the_tangent_is_the_derivative_of_the_stresses(name):
    law, p = _params(name, 0.3)
    lam = np.exp(np.random.default_rng(1).normal(0.0, 0.25, (20, 3)))
    d = law.dtau(lam, p)
    h = 1e-6
    fd = np.zeros_like(d)
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        fd[..., :, j] = (law.tau(lam * np.exp(e), p) - law.tau(lam * np.exp(-e), p)) / (2 * h)
    assert np.max(np.abs(fd - d)) <= 1e-7 * np.max(np.abs(d))
    assert np.allclose(d, np.swapaxes(d, -1, -2), rtol=1e-12, atol=1e-9 * np.abs(d).max())


@pytest.mark.parametrize("name", [n for n in LAWS if material_law(n).kind == "isochoric"])
def test_isochoric_laws_do_not_feel_a_dilation(name):
    law, p = _params(name, 0.3)
    lam = np.exp(np.random.default_rng(2).normal(0.0, 0.25, (10, 3)))
    t = law.tau(lam, p)
    assert np.allclose(law.tau(1.3 * lam, p), t, rtol=1e-10, atol=1e-9 * np.abs(t).max())
    assert np.allclose(t.sum(axis=-1), 0.0, atol=1e-9 * np.abs(t).max())  # deviatoric


def test_incompressible_compression_matches_the_closed_forms():
    eps = np.linspace(0.0, 0.67, 12)
    lam = 1.0 - eps
    i1 = lam**2 + 2.0 / lam
    cases = [
        ("neo-hookean", {"mu": 20e3}, 20e3 * (lam - lam**-2)),
        ("mooney-rivlin", {"C10": 8e3, "C01": 2e3},
         2.0 * (lam - lam**-2) * (8e3 + 2e3 / lam)),
        ("yeoh", {"C10": 10e3, "C20": -400.0, "C30": 30.0},
         2.0 * (lam - lam**-2) * (10e3 - 800.0 * (i1 - 3) + 90.0 * (i1 - 3) ** 2)),
        ("ogden-2", {"mu_1": 4e3, "alpha_1": 5.0, "mu_2": -2e3, "alpha_2": -2.0},
         4e3 * (lam**4 - lam**-3.5) - 2e3 * (lam**-3 - lam**0)),
        ("exponential", {"mu": 20e3, "b": 0.7},
         20e3 * (lam - lam**-2) * np.exp(0.7 * (i1 - 3))),
    ]
    for name, p, nominal in cases:
        assert compression_stress(name, p, eps) == pytest.approx(-nominal, rel=1e-10,
                                                                 abs=1e-9), name


@pytest.mark.parametrize("nu", [0.0, 0.2, 0.4])
def test_the_foam_spreads_as_lambda_to_minus_nu(nu):
    law = material_law("hyperfoam-2")
    p = law.natural(E0, {"nu": nu, "alpha_1": 12.0, "alpha_2": -3.0, "w_1": 0.7}, nu)
    lam = np.linspace(0.35, 1.0, 8)
    assert lateral_stretch(law, p, lam) == pytest.approx(lam**-nu, rel=1e-12)
    beta = nu / (1 - 2 * nu)
    j = lam ** (1 - 2 * nu)
    tau1 = sum(2 * p[f"mu_{i}"] / p[f"alpha_{i}"] * (lam ** p[f"alpha_{i}"]
               - j ** (-p[f"alpha_{i}"] * beta)) for i in (1, 2))
    assert compression_stress(law, p, 1 - lam) == pytest.approx(-tau1 / lam, rel=1e-10,
                                                                abs=1e-9)


def test_a_foam_with_a_large_exponent_levels_off():
    law = material_law("hyperfoam")
    p = law.natural(100e3, {"nu": 0.0, "alpha_1": 20.0}, 0.0)
    s = compression_stress(law, p, np.array([0.1, 0.2, 0.3, 0.4]))
    assert s == pytest.approx([4.9e3, 6.2e3, 7.1e3, 8.3e3], rel=0.02)  # the docstring's numbers
    assert np.all(np.diff(s) > 0) and s[-1] < 0.25 * 100e3 * 0.4  # a plateau, still rising


def test_linear_is_hooke_and_chords_read_it_exactly():
    eps = np.array([0.0, 0.05, 0.2])
    assert compression_stress(LINEAR, {"E": 111e3}, eps) == pytest.approx(111e3 * eps)
    assert chord_modulus(LINEAR, {"E": 111e3}, 0.05, 0.2) == pytest.approx(111e3)


def test_engineering_stress_stiffens_so_a_window_reads_above_E0():
    # docs/design.md §14: a slope over a strain window is not the initial modulus
    law, p = _params("neo-hookean", 0.5)
    assert chord_modulus(law, p, 0.0, 0.05) > 1.03 * E0
    assert chord_modulus(law, p, 0.05, 0.20) > 1.2 * E0


def test_bad_strains_are_refused():
    for bad in (-0.1, 0.99, float("nan")):
        with pytest.raises(InputError, match="compressive strains"):
            compression_stress("neo-hookean", {"mu": 1e3}, bad)
