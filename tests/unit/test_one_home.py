"""One home per value (issue 45): E from E*, the default nu, emcee's seeding and the lag-1
autocorrelation are each written once; the package's code is searched (as syntax trees, not
text: docstrings and comments may quote the numbers)."""

from __future__ import annotations

import ast
import inspect
import math
from pathlib import Path

import numpy as np
import pytest

import palpbayes
from palpbayes.compression import resid_acf1
from palpbayes.contact import DEFAULT_NU, youngs_factor
from palpbayes.sensor_noise import acf1

PACKAGE = Path(palpbayes.__file__).resolve().parent
SOURCES = sorted(PACKAGE.rglob("*.py"))


def _trees():
    for path in SOURCES:
        yield path.relative_to(PACKAGE).as_posix(), ast.parse(path.read_text(encoding="utf-8"))


def _is_nu(node: ast.AST) -> bool:
    name = node.id if isinstance(node, ast.Name) else (
        node.attr if isinstance(node, ast.Attribute) else "")
    return name == "nu" or name.startswith("nu_") or name.endswith("_nu")


def _is_nu_squared(node: ast.AST) -> bool:
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
        return _is_nu(node.left) and isinstance(node.right, ast.Constant) and node.right.value == 2
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return _is_nu(node.left) and _is_nu(node.right)
    if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "square":
        return len(node.args) == 1 and _is_nu(node.args[0])
    return False


def test_E_from_E_star_is_written_once():
    places = [f"{rel}:{n.lineno}" for rel, tree in _trees() for n in ast.walk(tree)
              if isinstance(n, ast.BinOp) and isinstance(n.op, ast.Sub)
              and isinstance(n.left, ast.Constant) and n.left.value == 1
              and _is_nu_squared(n.right)]
    lines, first = inspect.getsourcelines(youngs_factor)
    home = {f"contact/__init__.py:{first + i}" for i in range(len(lines))}
    assert places and set(places) <= home, places  # its scalar and array branches only
    assert youngs_factor(0.3) == pytest.approx(0.91)
    np.testing.assert_allclose(youngs_factor(np.array([0.0, 0.5])), [1.0, 0.75])


def test_the_default_nu_is_one_constant():
    literal = []
    for rel, tree in _trees():
        for n in ast.walk(tree):
            pairs = []
            if isinstance(n, ast.arguments):
                args = n.posonlyargs + n.args
                pairs += list(zip(args[len(args) - len(n.defaults):], n.defaults, strict=True))
                pairs += [(a, d) for a, d in zip(n.kwonlyargs, n.kw_defaults, strict=True)
                          if d is not None]
                pairs = [(ast.Name(id=a.arg), d) for a, d in pairs]
            elif isinstance(n, ast.Call):
                pairs += [(ast.Name(id=k.arg or ""), k.value) for k in n.keywords]
            elif isinstance(n, ast.Assign | ast.AnnAssign):
                targets = n.targets if isinstance(n, ast.Assign) else [n.target]
                pairs += [(t, n.value) for t in targets if n.value is not None]
            literal += [f"{rel}:{v.lineno}" for t, v in pairs
                        if _is_nu(t) and isinstance(v, ast.Constant) and v.value == DEFAULT_NU]
    assert literal == [], f"write contact.DEFAULT_NU, not {DEFAULT_NU}: {literal}"


def test_emcee_is_seeded_through_its_public_api():
    private = [f"{rel}:{n.lineno}" for rel, tree in _trees() for n in ast.walk(tree)
               if isinstance(n, ast.Attribute) and n.attr == "_random"]
    assert private == []


def test_acf1_one_estimate_and_its_degenerate_conventions():
    rng = np.random.default_rng(3)
    e = rng.standard_normal(4000)
    x = np.empty_like(e)
    x[0] = e[0]
    for t in range(1, x.size):  # AR(1), phi 0.6
        x[t] = 0.6 * x[t - 1] + e[t]
    assert acf1(x) == pytest.approx(0.6, abs=0.04)
    c = x - x.mean()
    assert acf1(x) == pytest.approx(float(c[1:] @ c[:-1] / (c @ c)), rel=1e-12)
    assert resid_acf1(x) == acf1(x)  # the ground truth's column is the same estimate
    # a constant series or a single sample: 0 where a number must go on, NaN in a table
    assert acf1(np.full(10, 2.0)) == 0.0 and acf1([1.0]) == 0.0
    assert math.isnan(resid_acf1(np.full(10, 2.0))) and math.isnan(resid_acf1(np.ones(1)))
