"""The house rules that a count can keep (issue 57, tools/house_counts.py): a public function
with 10 or more parameters says why beside it, a module over 400 lines says why in it, and the
count itself is right."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _tool():
    spec = importlib.util.spec_from_file_location("house_counts", ROOT / "tools" /
                                                  "house_counts.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_public_function_with_many_parameters_says_why():
    without = [f for _, f, why in _tool().counts(ROOT)["many"] if not why]
    assert not without, (
        "public functions with 10 or more parameters and no '# Many parameters:' comment "
        f"above them (gather them in an options object, or say why): {without}")


def test_every_long_module_says_why():
    without = [m for _, m, why in _tool().counts(ROOT)["long"] if not why]
    assert not without, (
        "modules over 400 lines with no '# Long module:' comment (split off the second job, "
        f"or say why it is one): {without}")


def test_the_counts_count_what_they_say(tmp_path):
    pkg = tmp_path / "palpbayes"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    args = ", ".join(f"a{i}" for i in range(10))
    (pkg / "m.py").write_text(
        f"def wide({args}):\n    pass\n\n\n# Many parameters: a reason.\n"
        f"def said({args}, *, b=1):\n    pass\n\n\ndef _private({args}):\n    pass\n\n\n"
        "class C:\n    def narrow(self, x):\n        pass\n\n    def lonely(self):\n"
        "        pass\n" + "\n" * 400)
    (pkg / "said.py").write_text('"""Doc."""\n\n# Long module: one job.\n' + "\n" * 400)
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_m.py").write_text("from palpbayes.m import C\nC().lonely()\n"
                                                 "wide(*range(10))\n")
    c = _tool().counts(tmp_path)
    assert [(n, f, w) for n, f, w in c["many"]] == [(11, "m.py:said", True),
                                                     (10, "m.py:wide", False)]
    assert sorted((m, w) for _, m, w in c["long"]) == [("m.py", False), ("said.py", True)]
    assert c["test_only"] == ["m.py:C.lonely", "m.py:wide"]
