#!/usr/bin/env python
"""The house's three counts (issue 57): modules over 400 lines, public functions with 10 or
more parameters, and public functions only the tests call.

Usage::

    python tools/house_counts.py [REPO] [--list]

A function with many parameters may say why beside it, in a comment line right above its
``def`` (or its decorators) that starts ``# Many parameters:``; a long module in a comment line
of its own that starts ``# Long module:`` (right after its docstring); both are counted apart.

``REPO`` (default: this checkout) is a folder holding ``palpbayes/`` (a ``git worktree`` of an
older commit, to print the counts before a change).  A parameter is a named one (positional or
keyword; ``self``/``cls``, ``*args`` and ``**kwargs`` not counted); a function is public when
neither it nor its class starts with ``_``.  "Called only by tests": its name occurs in no
other file of ``palpbayes/``, ``notebooks/*.py``, ``examples/``, ``tools/``, ``benchmarks/``
or ``docs/*.md``, but in ``tests/``.
"""

from __future__ import annotations

import argparse
import ast
import re
import sys
from collections import Counter
from pathlib import Path

LONG_MODULE = 400
MANY_PARAMETERS = 10


def _files(root: Path, pattern: str) -> list[Path]:
    return sorted(root.glob(pattern)) if root.exists() else []


REASON = "# Many parameters:"
LONG_REASON = "# Long module:"


def _has_reason(lines: list[str], node) -> bool:
    first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
    k = first - 2
    while k >= 0 and lines[k].strip().startswith("#"):
        if lines[k].strip().startswith(REASON):
            return True
        k -= 1
    return False


def public_functions(pkg: Path):
    """(module path, qualified name, parameter count, a reason is written) of every public
    function and method."""
    for path in sorted(pkg.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        tree = ast.parse(text)
        stack = [(node, "") for node in tree.body]
        while stack:
            node, prefix = stack.pop()
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                stack.extend((n, f"{prefix}{node.name}.") for n in node.body)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                if node.name.startswith("_"):
                    continue
                a = node.args
                names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
                n = len([x for x in names if x not in ("self", "cls")])
                yield path, prefix + node.name, n, _has_reason(lines, node)


def counts(repo: Path) -> dict:
    pkg = repo / "palpbayes"
    sources = {p: p.read_text(encoding="utf-8").splitlines() for p in pkg.rglob("*.py")}
    modules = {p: len(lines) for p, lines in sources.items()}
    long = sorted(((n, p.relative_to(pkg).as_posix(),
                    any(x.startswith(LONG_REASON) for x in sources[p]))
                   for p, n in modules.items() if n > LONG_MODULE), reverse=True)
    funcs = list(public_functions(pkg))
    many = sorted(((n, f"{p.relative_to(pkg).as_posix()}:{q}", why) for p, q, n, why in funcs
                   if n >= MANY_PARAMETERS), reverse=True)
    texts = {p: p.read_text(encoding="utf-8", errors="replace") for p in [
        *modules, *_files(repo, "notebooks/*.py"), *_files(repo, "examples/**/*.py"),
        *_files(repo, "tools/*.py"), *_files(repo, "benchmarks/**/*.py"),
        *_files(repo, "docs/*.md"), *_files(repo, "README.md")]}
    words = re.compile(r"\b\w+\b")
    exported = re.compile(r"__all__\s*\+?=\s*\[[^\]]*\]|__all__\.(?:append|extend)\([^)]*\)")
    used: Counter = Counter()
    for t in texts.values():  # a name listed in __all__ is exported, not used
        used.update(words.findall(exported.sub(" ", t)))
    in_tests = set()
    for p in _files(repo, "tests/**/*.py"):
        in_tests.update(words.findall(p.read_text(encoding="utf-8", errors="replace")))
    defs: Counter = Counter()
    for t in texts.values():
        defs.update(re.findall(r"def (\w+)\b", t))
    test_only = []
    for path, qual, _, _ in funcs:
        name = qual.rsplit(".", 1)[-1]
        if name.startswith("__") or len(name) < 4:
            continue
        if used[name] - defs[name] == 0 and name in in_tests:
            test_only.append(f"{path.relative_to(pkg).as_posix()}:{qual}")
    return {"modules": len(modules), "lines": sum(modules.values()), "long": long,
            "many": many, "test_only": sorted(test_only)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("repo", nargs="?", type=Path, default=Path(__file__).resolve().parents[1])
    parser.add_argument("--list", action="store_true", help="list each item, not only counts")
    args = parser.parse_args(argv)
    c = counts(args.repo)
    print(f"{c['modules']} modules, {c['lines']:,} lines")
    said = sum(w for _, _, w in c["long"])
    print(f"modules over {LONG_MODULE} lines: {len(c['long'])} ({said} with the reason "
          f"written in them, {len(c['long']) - said} without)")
    if args.list:
        print("\n".join(f"  {n:5d}  {m}{'  (reason given)' if w else ''}"
                         for n, m, w in c["long"]))
    why = sum(w for _, _, w in c["many"])
    print(f"public functions with >= {MANY_PARAMETERS} parameters: {len(c['many'])} "
          f"({why} with the reason written beside them, {len(c['many']) - why} without)")
    if args.list:
        print("\n".join(f"  {n:5d}  {f}{'  (reason given)' if w else ''}"
                         for n, f, w in c["many"]))
    print(f"public functions only the tests call: {len(c['test_only'])}")
    if args.list:
        print("\n".join(f"  {f}" for f in c["test_only"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
