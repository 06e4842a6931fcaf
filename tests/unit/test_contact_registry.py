"""The contact-law registry: each law module registers itself, and a law registered anywhere
(here a toy one defined in this file) is usable by the whole package with no other edit."""

import dataclasses
import importlib
import math
import pkgutil

import numpy as np
import pandas as pd
import pytest

import palpbayes.contact as contact
from palpbayes.checks import exponent_check, law_exponent
from palpbayes.cli import main
from palpbayes.contact import (
    TIP_PARAMETERS,
    ContactLaw,
    Tip,
    exponent,
    fixed_exponents,
    force,
    get_law,
    k_from_modulus,
    modulus_from_k,
    prefactor,
    register,
    registered_kinds,
    registered_laws,
    shape,
    unregister,
)
from palpbayes.errors import GeometryError
from palpbayes.fitdata import ModelSpec, default_fit_fraction, prepare
from palpbayes.io.manifest import tip_columns, tip_from_row
from palpbayes.io.trace_csv import write_trace
from palpbayes.lsq import fit_lsq
from palpbayes.sim import simulate_trace

M_BLUNT = 1.25  # toy exponent, between the flat punch's 1 and Hertz's 1.5
E_TRUE = 111e3


def _blunt_prefactor(tip: Tip) -> float:
    """g = tan(alpha)·R^(2-m) [m^(2-m)] (a toy law, not from the literature)."""
    return math.tan(tip.half_angle) * tip.radius ** (2.0 - M_BLUNT)


def _blunt_shape(depth, tip: Tip):
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return _blunt_prefactor(tip) * d**M_BLUNT


def _blunt_law(kind: str = "blunt") -> ContactLaw:
    return ContactLaw(
        kind=kind, parameters=("radius", "half_angle"), shape=_blunt_shape, exponent=M_BLUNT,
        prefactor=_blunt_prefactor, reference="a toy law of tests/unit/test_contact_registry.py",
        name="blunt-cone", label="blunt cone", summary="Blunt cone: F = E*·g·d^1.25 (toy).",
        describe=lambda tip: f"blunt R={tip.radius:g} alpha={math.degrees(tip.half_angle):g}",
        order=60,
        scaled=lambda tip, f: Tip(tip.kind, radius=tip.radius * f, half_angle=tip.half_angle))


@pytest.fixture
def blunt():
    """A toy 'blunt cone' power law registered for one test, unregistered after."""
    law = register(_blunt_law())
    yield law
    unregister(law.kind)


BLUNT = {"radius": 0.01, "half_angle": math.radians(60)}


def _example_tip(law: ContactLaw) -> Tip:
    """A tip of ``law`` with the parameters' example values (as a user gives them)."""
    return Tip(law.kind, **{p: TIP_PARAMETERS[p].from_user(float(TIP_PARAMETERS[p].example))
                            for p in law.parameters})


def test_builtin_laws_register_themselves():
    """Every module of the package defining LAW registered it, and nothing else is."""
    found = {}
    for info in pkgutil.iter_modules(contact.__path__):
        module = importlib.import_module(f"palpbayes.contact.{info.name}")
        if hasattr(module, "LAW"):
            found[module.LAW.kind] = module.LAW
    assert set(found) == set(registered_kinds())
    assert all(get_law(kind) is law for kind, law in found.items())
    assert registered_kinds() == ("flat", "sphere", "paraboloid", "cone", "power")
    assert contact.TIP_KINDS == registered_kinds()


def test_tip_parameters_are_the_tip_fields():
    fields = [f.name for f in dataclasses.fields(Tip) if f.name != "kind"]
    assert list(TIP_PARAMETERS) == fields


@pytest.mark.parametrize("law", registered_laws(), ids=lambda law: law.kind)
def test_every_law_is_complete(law):
    tip = _example_tip(law)
    assert law.reference and law.summary and law.name and law.label
    assert tip.describe().startswith(law.kind)
    d = np.linspace(0.0, 2e-3, 50)
    s = shape(d, tip)
    assert s[0] == 0.0 and np.all(np.diff(s) > 0)
    assert shape(np.array([-1e-3]), tip)[0] == 0.0
    if law.exponent is not None:
        assert s[1:] == pytest.approx(prefactor(tip) * d[1:] ** exponent(tip), rel=1e-12)
    assert tip.scaled(1.0) == tip and tip.has_length_scale == (law.scaled is not None)
    # manifest columns round-trip
    row = pd.Series({"trace_id": "a", "tip": law.kind, **tip_columns(tip)})
    assert tip_from_row(row) == tip


def test_duplicate_registration_is_refused(blunt):
    with pytest.raises(ValueError, match="registered already"):
        register(_blunt_law())
    with pytest.raises(ValueError, match="registered already"):
        register(dataclasses.replace(get_law("flat")))


def test_law_definition_is_checked():
    with pytest.raises(ValueError, match="unknown tip parameter"):
        dataclasses.replace(_blunt_law(), parameters=("width",))
    with pytest.raises(ValueError, match="both exponent and prefactor"):
        dataclasses.replace(_blunt_law(), prefactor=None)
    with pytest.raises(ValueError, match="lower-case identifier"):
        dataclasses.replace(_blunt_law(), kind="Blunt Cone")


def test_unregistered_kind_is_unknown():
    law = register(_blunt_law("wedge2"))
    assert Tip("wedge2", **BLUNT).kind == "wedge2"
    assert unregister("wedge2") is law
    with pytest.raises(GeometryError, match="unknown tip kind 'wedge2'; use one of flat, "):
        Tip("wedge2", **BLUNT)


def test_new_law_through_tip_force_and_exponent(blunt):
    tip = Tip("Blunt", **BLUNT)
    assert tip.kind == "blunt" and "blunt" in contact.TIP_KINDS
    assert registered_kinds()[-1] == "blunt"  # order 60: after the built-in laws
    with pytest.raises(GeometryError, match="cone half-angle \\[rad\\] is missing"):
        Tip("blunt", radius=0.01)
    d = np.linspace(-1e-3, 3e-3, 41)
    nu = 0.3
    expected = E_TRUE / (1 - nu**2) * _blunt_prefactor(tip) * np.clip(d, 0, None) ** M_BLUNT
    assert force(d, E_TRUE, nu, tip) == pytest.approx(expected, rel=1e-14, abs=0)
    assert exponent(tip) == M_BLUNT and fixed_exponents()["blunt"] == M_BLUNT
    k = k_from_modulus(E_TRUE, nu, tip)
    assert modulus_from_k(k, nu, tip) == pytest.approx(E_TRUE, rel=1e-14)
    assert default_fit_fraction(tip) == 0.0
    with pytest.raises(GeometryError,
                       match="no layer \\(finite-thickness\\) solution for tip 'blunt'"):
        shape(d, tip, thickness_m=0.02, nu=nu)
    assert tip.scaled(1.01).radius == pytest.approx(0.0101)


def test_new_law_exponent_check_and_least_squares(blunt):
    tip = Tip("blunt", **BLUNT)
    tr = simulate_trace(E_TRUE, tip, thickness=0.03, noise_pp=0.0, rng=0, base=None)
    r = fit_lsq(tr, f_unc=48e-3)
    assert r.E == pytest.approx(E_TRUE, rel=1e-6)
    assert r.m == M_BLUNT

    noisy = simulate_trace(E_TRUE, tip, thickness=0.03, rng=1, base=None)
    r = fit_lsq(noisy)
    assert r.E == pytest.approx(E_TRUE, rel=0.02)
    data = prepare(noisy, ModelSpec(tip))
    assert law_exponent(data.model, data.z, r.z_surf) == M_BLUNT
    check = exponent_check(data.z, data.force, data.model, r.z_surf)
    assert check.details["m_law"] == M_BLUNT and check.passed
    # the same data under the Hertz law: the check fails and names the toy law's exponent
    wrong = ModelSpec(Tip("paraboloid", radius=0.01))
    check = exponent_check(data.z, data.force, wrong, r.z_surf)
    assert not check.passed and "blunt law's 1.25" in check.flag


def test_new_law_from_the_command_line(blunt, tmp_path):
    tr = simulate_trace(E_TRUE, Tip("blunt", **BLUNT), thickness=0.03, rng=2, base=None)
    path = tmp_path / "blunt.csv"
    write_trace(tr, path)
    out = tmp_path / "res"
    assert main(["fit", str(path), "--tip", "blunt", "--radius", "0.01", "--half-angle", "60",
                 "--method", "lsq", "--out", str(out)]) == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert row["tip"] == "blunt" and row["E_pa"] == pytest.approx(E_TRUE, rel=0.02)
