"""The noise models have one home (issue 57): every option, check and fallback reads the
registry, so a new model is a row there plus its log-likelihood."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from palpbayes.bayes.noisemodels import (
    EXACT_NOISE_MODELS,
    NOISE_MODELS,
    NOISE_REGISTRY,
    exact_noise,
    get_noise_model,
)
from palpbayes.bayes.priors import param_names
from palpbayes.errors import InputError

PACKAGE = Path(__file__).resolve().parents[2] / "palpbayes"


def test_the_registry_names_each_model_and_its_extra_parameter():
    assert NOISE_MODELS == ("gaussian", "ar1", "student")
    assert EXACT_NOISE_MODELS == ("gaussian", "ar1")
    for name, model in NOISE_REGISTRY.items():
        names = param_names(name)
        assert names[:4] == ["log_Estar", "z_surf", "log_sigma", "F0"]
        assert names[4:] == ([model.extra] if model.extra else [])
    assert exact_noise("student") == "gaussian" and exact_noise("ar1") == "ar1"
    with pytest.raises(InputError, match="unknown noise model 'pink'.*gaussian, ar1, student"):
        get_noise_model("pink")
    with pytest.raises(InputError, match="unknown noise model"):
        param_names("pink")


def test_no_module_spells_the_model_list_itself():
    """A tuple or list of two or more noise-model names written out anywhere but the registry
    is a second home that a new model would have to find."""
    names = set(NOISE_MODELS)
    homes = []
    for path in PACKAGE.rglob("*.py"):
        if path.name == "noisemodels.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Tuple | ast.List | ast.Set):
                vals = {e.value for e in node.elts if isinstance(e, ast.Constant)}
                if len(vals & names) >= 2:
                    homes.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert not homes, homes


def test_the_command_lines_offer_the_registry():
    from palpbayes.cli import build_parser

    parser = build_parser()
    seen = {}
    for action in parser._subparsers._group_actions[0].choices.items():
        cmd, sub = action
        for a in sub._actions:
            if "--noise" in a.option_strings:
                seen[cmd] = tuple(a.choices)
    assert seen["fit"] == NOISE_MODELS
    for cmd in ("map", "follow", "replay"):
        if cmd in seen:
            assert seen[cmd] == EXACT_NOISE_MODELS, cmd
    assert len(seen) >= 3
