"""palpbayes has no import cycle and no dangling relative import, counting function-level
imports (tools/import_graph.py)."""

import importlib.util
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "import_graph.py"


def _tool():
    spec = importlib.util.spec_from_file_location("import_graph", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_no_import_cycles():
    tool = _tool()
    assert tool.cycles(tool.graph()) == []


def test_no_cycles_between_parts():
    """Subpackages and top-level modules import one way too (issue 57: campaign -> gap -> sim
    -> rheology -> campaign through campaign/layout, and io -> twin -> io through the
    specimen and the atomic writes, hid behind a module-level check)."""
    tool = _tool()
    assert tool.cycles(tool.layers(tool.graph())) == []


def test_every_relative_import_names_a_module_that_exists():
    assert _tool().unresolved() == []


def test_a_relative_import_left_behind_by_a_move_is_found(tmp_path):
    """``from .paper import X`` inside a function of a module moved into a subpackage fails
    only when the function runs; the tool finds it statically."""
    tool = _tool()
    pkg = tmp_path / "palpbayes"
    (pkg / "campaign").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "paper.py").write_text("X = 1\n")
    (pkg / "campaign" / "__init__.py").write_text("")
    (pkg / "campaign" / "reference.py").write_text(
        "from .. import paper\n\ndef f():\n    from .paper import X\n    return X\n")
    assert tool.unresolved(pkg) == [
        "palpbayes/campaign/reference.py:4: no module palpbayes.campaign.paper"]


def test_cycle_check_finds_cycles_and_function_level_imports(tmp_path, capsys):
    tool = _tool()
    pkg = tmp_path / "palpbayes"
    (pkg / "io").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "io" / "__init__.py").write_text("")
    (pkg / "io" / "a.py").write_text("from .b import f\n")
    (pkg / "io" / "b.py").write_text("def f():\n    from . import a\n    return a\n")
    (pkg / "c.py").write_text("from .io import a\nimport palpbayes.io.b\n")
    edges = tool.graph(pkg)
    assert edges["palpbayes.io.a"] == {"palpbayes.io.b"}
    assert edges["palpbayes.io.b"] == {"palpbayes.io.a"}
    assert edges["palpbayes.c"] == {"palpbayes.io.a", "palpbayes.io.b"}
    assert tool.cycles(edges) == [["palpbayes.io.a", "palpbayes.io.b"]]
    text = tool.dot(edges, pkg)
    assert text.startswith("digraph") and '"palpbayes.c" -> "palpbayes.io.a";' in text
    assert 'label="palpbayes.io";' in text


def test_cli_exit_status(capsys):
    assert _tool().main([]) == 0
    assert "no import cycles" in capsys.readouterr().out
    assert _tool().main(["--dot"]) == 0
    assert capsys.readouterr().out.startswith("digraph palpbayes {")


def _hand_table_parts() -> set[str]:
    """The parts named in the first column of docs/layout.md's table "The parts and their one
    job" (``campaign/`` -> campaign, ``api.py`` -> api, ``__init__.py`` -> palpbayes)."""
    import re

    text = _tool().LAYOUT.read_text(encoding="utf-8")
    table = text.split("## The parts and their one job", 1)[1].split("\n\n", 2)[1]
    names = set()
    for row in table.splitlines()[2:]:
        first = row.split("|")[1]
        names |= {n.rstrip("/").removesuffix(".py") for n in re.findall(r"`([^`]+)`", first)}
    return {"palpbayes" if n == "__init__" else n for n in names}


def test_docs_layout_matches_the_code():
    """docs/layout.md's generated block (parts, modules, arrows, long modules) is what the code
    gives now, and its hand-written table has a row for every part and none for a gone one."""
    tool = _tool()
    assert tool.documented_block() == tool.layout_block(), (
        "docs/layout.md is stale: run python tools/import_graph.py --layout")
    parts = set(tool.layers(tool.graph()))
    hand = _hand_table_parts()
    assert not parts - hand, f"parts without a row in docs/layout.md: {sorted(parts - hand)}"
    assert not hand - parts, f"rows of docs/layout.md naming no part: {sorted(hand - parts)}"
