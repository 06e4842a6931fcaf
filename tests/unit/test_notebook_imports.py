"""The notebooks use only palpbayes' public names (issue 45).

Public: a name in ``palpbayes.__all__``, or a name in the ``__all__`` of a subpackage that is
itself in ``palpbayes.__all__`` (``pb.plots.plot_forest``, ``from palpbayes.twin import
Specimen``).  Reaching into a module file (``palpbayes.fitdata.prepare``) is not.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import palpbayes

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "notebooks").glob("*.py"))


def _is_public(chain: list[str]) -> bool:
    """``chain`` = attribute names after ``palpbayes`` (e.g. ["plots", "plot_forest"])."""
    if not chain:
        return True
    head, *rest = chain
    if head.startswith("__"):  # __version__, __file__
        return True
    if head not in palpbayes.__all__:
        return False
    if not rest:
        return True
    value = getattr(palpbayes, head)
    if not hasattr(value, "__path__") and not hasattr(value, "__file__"):
        return True  # an attribute of a public class or function (f.summary, Tip.sphere)
    return rest[0] in getattr(value, "__all__", ())


def violations(source: str) -> list[str]:
    """The non-public palpbayes names a notebook's source uses, as ``line: name``."""
    tree = ast.parse(source)
    aliases: dict[str, list[str]] = {}  # local name -> chain after "palpbayes"
    bad: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                if parts[0] != "palpbayes":
                    continue
                if not _is_public(parts[1:]):
                    bad.append(f"{node.lineno}: import {a.name}")
                if a.asname:
                    aliases[a.asname] = parts[1:]
                else:
                    aliases["palpbayes"] = []
        elif isinstance(node, ast.ImportFrom) and node.module and (
                node.module.split(".")[0] == "palpbayes"):
            base = node.module.split(".")[1:]
            for a in node.names:
                chain = [*base, a.name]
                if not _is_public(chain):
                    bad.append(f"{node.lineno}: from {node.module} import {a.name}")
                aliases[a.asname or a.name] = chain
    inner = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and id(node) not in inner:  # whole chains only
            chain: list[str] = []
            cur: ast.expr = node
            while isinstance(cur, ast.Attribute):
                chain.insert(0, cur.attr)
                cur = cur.value
            if isinstance(cur, ast.Name) and cur.id in aliases:
                full = aliases[cur.id] + chain
                # only the first two links are the package's (the rest are attributes)
                if not _is_public(full[:2]):
                    bad.append(f"{node.lineno}: {cur.id}.{'.'.join(chain)}")
    return sorted(set(bad), key=lambda s: int(s.split(":")[0]))


def test_the_rule_catches_internals():
    src = ("import palpbayes as pb\nfrom palpbayes.fitdata import prepare\n"
           "from palpbayes import plots\nx = pb.bayes.fit_bayes\ny = plots.plot_forest\n"
           "z = pb.fit\nfrom palpbayes.twin import Specimen\nw = pb.twin.fe\n"
           "v = pb.__version__\nfrom palpbayes.contact.layer import flat_table\n"
           "import palpbayes.lsq\nu = pb.fit(1).E\n")
    assert violations(src) == ["2: from palpbayes.fitdata import prepare",
                               "4: pb.bayes.fit_bayes", "8: pb.twin.fe",
                               "10: from palpbayes.contact.layer import flat_table",
                               "11: import palpbayes.lsq"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_uses_only_public_names(path):
    bad = violations(path.read_text(encoding="utf-8"))
    assert not bad, f"{path.name} uses palpbayes internals:\n" + "\n".join(bad)
