#!/usr/bin/env python
"""Import graph of the palpbayes package: find cycles, or print it as Graphviz DOT.

Every ``import`` / ``from ... import`` statement in ``palpbayes/`` counts, including those inside
functions (a function-level import hides a cycle from Python's import machinery, not from this
check).  Edges go module -> module within palpbayes; ``from . import x`` resolves to the
submodule ``x`` when one exists, else to the package (its ``__init__``).

Usage::

    python tools/import_graph.py          # print cycles (between modules, and between parts:
                                          # subpackages and top-level modules) and relative
                                          # imports of modules that do not exist; exit 1 if
                                          # there are any, else 0
    python tools/import_graph.py --dot    # Graphviz DOT of module -> module edges, one
                                          # cluster per subpackage
    python tools/import_graph.py --layout # rewrite docs/layout.md's generated block: every
                                          # part, its modules and the parts it imports, and
                                          # the modules over 400 lines (a test compares it)
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Iterable
from pathlib import Path

PACKAGE = "palpbayes"
ROOT = Path(__file__).resolve().parents[1] / PACKAGE


def modules(root: Path = ROOT) -> dict[str, Path]:
    """Dotted module name -> file, for every .py file under ``root`` (packages by __init__)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _resolve(name: str, mods: dict[str, Path]) -> str | None:
    """The longest prefix of ``name`` that is a palpbayes module (None outside the package)."""
    parts = name.split(".")
    while parts:
        candidate = ".".join(parts)
        if candidate in mods:
            return candidate
        parts.pop()
    return None


def imports_of(module: str, mods: dict[str, Path]) -> set[str]:
    """Palpbayes modules imported anywhere in ``module`` (module level or inside functions)."""
    tree = ast.parse(mods[module].read_text(encoding="utf-8"), filename=str(mods[module]))
    is_package = mods[module].name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                if node.level > 1:
                    base = base[: len(base) - (node.level - 1)]
                stem = ".".join(base + ([node.module] if node.module else []))
            else:
                stem = node.module or ""
            # ``from pkg import sub`` imports the submodule pkg.sub when there is one
            targets = [f"{stem}.{alias.name}" if f"{stem}.{alias.name}" in mods else stem
                       for alias in node.names]
        else:
            continue
        for target in targets:
            resolved = _resolve(target, mods)
            if resolved is not None and resolved != module:
                found.add(resolved)
    return found


def graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> set of palpbayes modules it imports."""
    mods = modules(root)
    return {module: imports_of(module, mods) for module in mods}


def unresolved(root: Path = ROOT) -> list[str]:
    """Relative imports (anywhere in a module, functions included) whose module does not exist:
    ``from .paper import X`` left behind in a module that moved into a subpackage.  Python
    finds these only when the line runs; this finds them all at once."""
    mods = modules(root)
    out = []
    for module, path in mods.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(tree):
            if not (isinstance(node, ast.ImportFrom) and node.level):
                continue
            base = package.split(".")
            if node.level > 1:
                base = base[: len(base) - (node.level - 1)]
            stem = ".".join(base + ([node.module] if node.module else []))
            if stem not in mods:
                out.append(f"{path.relative_to(root.parent)}:{node.lineno}: no module {stem}")
    return out


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (or a self-loop), each
    sorted, by Tarjan's algorithm (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for start in sorted(edges):
        if start in index:
            continue
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges.get(child, ())))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1 or node in edges.get(node, ()):
                    out.append(sorted(component))
    return sorted(out)


def dot(edges: dict[str, set[str]], root: Path = ROOT) -> str:
    """Graphviz DOT text: one node per module, clustered by (sub)package; a package's node
    (its ``__init__``) sits in its own cluster."""
    mods = modules(root)
    groups: dict[str, list[str]] = {}
    for module in edges:
        is_package = module in mods and mods[module].name == "__init__.py"
        group = module if is_package else module.rpartition(".")[0]
        groups.setdefault(group, []).append(module)
    lines = [f"digraph {PACKAGE} {{", "  rankdir=LR;", "  node [shape=box, fontsize=10];"]
    for i, (group, members) in enumerate(sorted(groups.items())):
        lines.append(f'  subgraph cluster_{i} {{')
        lines.append(f'    label="{group}";')
        lines.extend(f'    "{m}";' for m in sorted(members))
        lines.append("  }")
    for module in sorted(edges):
        lines.extend(f'  "{module}" -> "{target}";' for target in sorted(edges[module]))
    lines.append("}")
    return "\n".join(lines) + "\n"


def layers(edges: dict[str, set[str]]) -> dict[str, set[str]]:
    """The graph collapsed to subpackages and top-level modules (``palpbayes.bayes.fit`` ->
    ``bayes``; the package's own ``__init__`` -> ``palpbayes``), self-edges dropped."""
    def group(module: str) -> str:
        parts = module.split(".")
        return parts[1] if len(parts) > 1 else PACKAGE

    out: dict[str, set[str]] = {}
    for module, targets in edges.items():
        a = group(module)
        out.setdefault(a, set())
        out[a] |= {group(t) for t in targets} - {a}
    return out


#: Leaf modules that nearly every module imports; left out of the drawing to keep it legible.
LEAVES = ("errors", "units")


def layers_dot(edges: dict[str, set[str]], hide: Iterable[str] = LEAVES) -> str:
    """Graphviz DOT of :func:`layers`, drawn top-down: every arrow points to a lower layer.
    Arrows into the ``hide`` leaves (imported nearly everywhere, importing nothing) are left
    out and the leaves named in a note."""
    hide = set(hide)
    lay = {a: t - hide for a, t in layers(edges).items() if a not in hide}
    lines = [f"digraph {PACKAGE}_layers {{", "  rankdir=TB; ranksep=0.35; nodesep=0.15;",
             '  node [shape=box, style="rounded,filled", fillcolor="#eef3fa", fontsize=11, '
             'fontname="Helvetica"];', '  edge [color="#7a8aa0", arrowsize=0.6];']
    lines.extend(f'  "{n}";' for n in sorted(lay))
    if hide:
        lines.append(f'  note [shape=note, fillcolor="#ffffff", label="not drawn: '
                     f'{", ".join(sorted(hide))}\\n(leaves imported nearly everywhere)"];')
    for a in sorted(lay):
        lines.extend(f'  "{a}" -> "{t}";' for t in sorted(lay[a]))
    lines.append("}")
    return "\n".join(lines) + "\n"


#: docs/layout.md and the markers around the block :func:`layout_block` writes there.
LAYOUT = ROOT.parent / "docs" / "layout.md"
BEGIN = "<!-- begin: generated by `python tools/import_graph.py --layout`; do not edit -->"
END = "<!-- end of the generated block -->"
#: A module this long has a second job or wants an options object (the house rule).
LONG = 400


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def layout_block(root: Path = ROOT) -> str:
    """The generated block of docs/layout.md: one row per part (subpackage or top-level
    module) with its modules, its lines (a subpackage's to the nearest 500, a module's to the
    nearest 50) and the parts it imports
    (:func:`layers`, ``errors`` and ``units`` left out as everywhere), then the modules over
    :data:`LONG` lines (to the nearest 50, at least ~450)."""
    mods = modules(root)
    parts = layers(graph(root))
    lines = {module: _lines(path) for module, path in mods.items()}  # each file read once
    count: dict[str, list[int]] = {}
    for module, n in lines.items():
        bits = module.split(".")
        part = bits[1] if len(bits) > 1 else PACKAGE
        count.setdefault(part, []).append(n)
    rows = ["| part | modules | lines | imports |", "|---|---|---|---|"]
    for part in sorted(parts):
        name = f"`{part}/`" if (root / part).is_dir() else (
            "`__init__.py`" if part == PACKAGE else f"`{part}.py`")
        arrows = ", ".join(sorted("__init__" if t == PACKAGE else t
                                  for t in parts[part] - set(LEAVES))) or "-"
        total, step = sum(count[part]), 500 if (root / part).is_dir() else 50
        rows.append(f"| {name} | {len(count[part])} | ~{max(step, round(total / step) * step):,} "
                    f"| {arrows} |")
    long = sorted(((n, m) for m, n in lines.items() if n > LONG), reverse=True)
    over = "; ".join(f"`{m.removeprefix(PACKAGE + '.').replace('.', '/')}.py` "
                     f"~{max(450, round(n / 50) * 50)}" for n, m in long)
    return "\n".join([
        BEGIN, "", f"{len(mods)} modules in {len(parts)} parts; every part imports `errors` "
        "and `units` freely (not listed).", "", *rows, "",
        f"Modules over {LONG} lines ({len(long)}): {over}.", "", END])


def write_layout(path: Path = LAYOUT, root: Path = ROOT) -> bool:
    """Replace the generated block of ``path`` with :func:`layout_block`; True if it
    changed."""
    text = path.read_text(encoding="utf-8")
    head, _, rest = text.partition(BEGIN)
    if BEGIN not in text or END not in rest:
        raise SystemExit(f"{path}: the markers of the generated block are missing or broken "
                         f"({BEGIN!r} ... {END!r}); put them back where the block goes")
    _, _, tail = rest.partition(END)
    new = head + layout_block(root) + tail
    if new != text:
        path.write_text(new, encoding="utf-8")
    return new != text


def documented_block(path: Path = LAYOUT) -> str:
    """The generated block as docs/layout.md holds it now ('' without markers)."""
    text = path.read_text(encoding="utf-8")
    if BEGIN not in text:
        return ""
    return BEGIN + text.partition(BEGIN)[2].partition(END)[0] + END


def main(argv: Iterable[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dot", action="store_true",
                        help="print a Graphviz DOT of module -> module edges instead")
    parser.add_argument("--layers", action="store_true",
                        help="print a Graphviz DOT of the subpackage-level graph instead "
                             "(docs/import-graph.svg: dot -Tsvg)")
    parser.add_argument("--layout", action="store_true",
                        help="rewrite the generated block of docs/layout.md (parts, modules, "
                             "arrows, long modules) from the code")
    args = parser.parse_args(list(argv) if argv is not None else None)
    if args.layout:
        print(f"{LAYOUT}: " + ("updated" if write_layout() else "already matches the code"))
        return 0
    edges = graph()
    if args.layers:
        sys.stdout.write(layers_dot(edges))
        return 0
    if args.dot:
        sys.stdout.write(dot(edges))
        return 0
    missing = unresolved()
    for line in missing:
        print(f"unresolved relative import: {line}")
    found = cycles(edges)
    parts = layers(edges)
    found_parts = cycles(parts)
    n_edges = sum(len(t) for t in edges.values())
    if not found and not found_parts and not missing:
        print(f"no import cycles ({len(edges)} modules, {n_edges} edges; {len(parts)} parts)")
        return 0
    for graph_, component in [(edges, c) for c in found] + [(parts, c) for c in found_parts]:
        print(("import cycle: " if graph_ is edges else "cycle between parts: ")
              + " <-> ".join(component))
        for module in component:
            inside = sorted(graph_[module] & set(component))
            print(f"  {module} -> {', '.join(inside)}")
    return 1 if found or found_parts or missing else 0


if __name__ == "__main__":
    sys.exit(main())
