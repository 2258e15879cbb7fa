"""Count what issue 25 asks to remove, from the source alone (``ast``; nothing is imported).

Prints, per package:
- import circles: strongly connected components of the module import graph (modules that
  import each other, directly or around a ring), with their members;
- arrows back up: imports against the layering of docs/architecture.md
  (``firmware_protocol`` ← ``virtual_drive``, ``drive_link`` ← ``dashboard``;
  ``drive_link`` never imports ``virtual_drive``; inside ``drive_link`` its folders
  ``cli`` → ``workflows`` → ``link`` → ``errors``/``_jsonable``, the facade outside them);
- private-field reaches: ``obj._name`` read or written where ``obj`` is neither ``self`` nor
  ``cls`` and ``_name`` is an attribute (not a module's private function reached through an
  import alias, which ``from x import _f`` would show just the same);
- hand-written modules over 600 lines (the generated C header excluded).

Run: ``python benchmarks/architecture_counts.py`` (add ``--json`` for a machine-readable copy).
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("firmware_protocol", "virtual_drive", "drive_link", "dashboard")
#: which package may import which (docs/architecture.md): an arrow not listed goes back up
ALLOWED = {
    "firmware_protocol": set(),
    "virtual_drive": {"firmware_protocol"},
    "drive_link": {"firmware_protocol"},
    "dashboard": {"firmware_protocol", "drive_link", "virtual_drive"},
}
#: drive_link's folders, top to bottom (docs/architecture.md): an import goes down only
FOLDERS = {"cli": 0, "workflows": 1, "link": 2, "errors": 3, "_jsonable": 3}
GENERATED = {"firmware_protocol/bldc_drive_od.h"}
MAX_LINES = 600


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            out[module_name(path)] = path
    return out


def resolve(mod: str, node: ast.ImportFrom, is_pkg: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = mod.split(".")
    base = base if is_pkg else base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports(mods: dict[str, Path], typing: bool = False) -> dict[str, set[str]]:
    """module -> the project modules it imports, at any depth in the file; imports under
    ``if TYPE_CHECKING`` only with ``typing`` (they are no import-time arrows, but a module
    that names another's type for the checker still depends on it)."""
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        tree = ast.parse(path.read_text(), str(path))
        skip: set[int] = set()
        for node in ast.walk(tree):
            if (not typing and isinstance(node, ast.If)
                    and "TYPE_CHECKING" in ast.unparse(node.test)):
                skip.update(id(n) for b in node.body for n in ast.walk(b))
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = resolve(mod, node, path.name == "__init__.py")
                targets = [f"{base}.{a.name}" for a in node.names]
                if any(t not in mods for t in targets):  # a name from the module ``base``
                    targets.append(base)
            for t in targets:
                if t not in mods and t.rpartition(".")[0] not in mods:
                    t = t.rpartition(".")[0]
                while t and t not in mods:
                    t = t.rpartition(".")[0]
                if t and t != mod:
                    graph[mod].add(t)
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one member."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]
    sys.setrecursionlimit(10_000)

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return sorted(out)


def back_arrows(graph: dict[str, set[str]]) -> list[str]:
    out = []
    for a, targets in graph.items():
        pa = a.split(".")[0]
        for b in targets:
            pb = b.split(".")[0]
            if pa != pb and pb not in ALLOWED[pa]:
                out.append(f"{a} -> {b}")
            elif pa == pb == "drive_link":
                fa = FOLDERS.get(a.split(".")[1] if "." in a else "")
                fb = FOLDERS.get(b.split(".")[1] if "." in b else "")
                if fa is not None and fb is not None and fb < fa:
                    out.append(f"{a} -> {b}")
    return sorted(out)


def reaches(path: Path) -> list[str]:
    """``file:line: obj._field`` for each reach into another object's private field in
    ``path``: ``obj`` neither ``self``/``cls`` nor an imported module or name."""
    tree = ast.parse(path.read_text(), str(path))
    names = {"self", "cls"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.asname or a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            names |= {a.asname or a.name for a in node.names}
    return [
        f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute)
        and node.attr.startswith("_")
        and not node.attr.startswith("__")
        and not (isinstance(node.value, ast.Name) and node.value.id in names)
    ]


def private_reaches(mods: dict[str, Path]) -> dict[str, int]:
    """module -> count of :func:`reaches` in it."""
    return {mod: n for mod, path in mods.items() if (n := len(reaches(path)))}


def long_files() -> dict[str, int]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*")):
            if path.suffix not in (".py", ".c", ".h") or "static" in path.parts:
                continue
            rel = str(path.relative_to(ROOT))
            if rel in GENERATED:
                continue
            lines = len(path.read_text().splitlines())
            if lines > MAX_LINES:
                out[rel] = lines
    return out


def counts() -> dict:
    mods = modules()
    graph = imports(mods)
    reaches = private_reaches(mods)
    return {
        "modules": len(mods),
        "import_arrows": sum(len(t) for t in graph.values()),
        "circles": circles(graph),
        "circles_with_type_imports": circles(imports(mods, typing=True)),
        "back_arrows": back_arrows(graph),
        "private_reaches": reaches,
        "private_reaches_total": sum(reaches.values()),
        "files_over_600_lines": long_files(),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    c = counts()
    if args.json:
        print(json.dumps(c, indent=1))
        return 0
    print(f"{c['modules']} modules, {c['import_arrows']} import arrows")
    print(f"import circles: {len(c['circles'])}")
    for comp in c["circles"]:
        print(f"  {len(comp)} modules: {', '.join(comp)}")
    print("import circles counting imports for the type checker only: "
          f"{len(c['circles_with_type_imports'])}")
    for comp in c["circles_with_type_imports"]:
        print(f"  {len(comp)} modules: {', '.join(comp)}")
    print(f"arrows back up: {len(c['back_arrows'])}")
    for arrow in c["back_arrows"]:
        print(f"  {arrow}")
    print(f"private-field reaches: {c['private_reaches_total']}")
    for mod, n in sorted(c["private_reaches"].items(), key=lambda kv: -kv[1]):
        print(f"  {n:4d} {mod}")
    print(f"hand-written files over {MAX_LINES} lines: {len(c['files_over_600_lines'])}")
    for f, n in c["files_over_600_lines"].items():
        print(f"  {n:5d} {f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
