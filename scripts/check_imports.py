#!/usr/bin/env python3
"""Imports run one way: no circle between the files of the Rust library (src/) or of the add-on (blender_addon/),
and no module of the library reaches back up to the crate root for a name the root only re-exports.

A file-level graph: in Rust an edge is a `crate::a::b` or `super::` path written anywhere outside comments and the
unit-test module (a `mod` line is not an edge, nor a module's use of its own parent); in Python an import of one of
the package's own modules. Circles are the graph's strongly connected components of more than one file. Prints each
with the names that tie it and exits 1; prints "imports: one-way" and exits 0 when there is none. Run by
scripts/lint.sh; an argument names another project root (tests/python/test_check_imports.py).
"""

from __future__ import annotations

import ast
import pathlib
import re
import sys
from collections import defaultdict

ROOT = pathlib.Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[1]
RUST_PATH = re.compile(r"\b(crate|super)((?:::[A-Za-z_]\w*)+)")
RUST_GROUP = re.compile(r"\buse\s+(crate|super)((?:::\w+)*)::\{([^;]*)\}\s*;", re.S)
COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
TEST_MODULE = re.compile(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{")
OWN_ITEM = re.compile(r"\b(?:struct|enum|fn|mod|const|static|type|trait)\s+(\w+)")


def rust_modules(src: pathlib.Path) -> dict[tuple[str, ...], pathlib.Path]:
    """Module path -> file for the library's files (src/bin is another crate)."""
    modules = {}
    for path in src.rglob("*.rs"):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts[0] == "bin":
            continue
        if parts[-1] in ("mod", "lib"):
            parts.pop()
        modules[tuple(parts)] = path
    return modules


def rust_code(path: pathlib.Path) -> str:
    text = COMMENT.sub("", path.read_text(encoding="utf-8"))
    test = TEST_MODULE.search(text)
    return text[: test.start()] if test else text


def resolve(modules, here: tuple[str, ...], root: str, names: list[str]) -> tuple[tuple[str, ...], str] | None:
    """The file a path names (its longest module prefix) and the name it takes there."""
    base = () if root == "crate" else here[:-1]
    full = base + tuple(names)
    for cut in range(len(full), -1, -1):
        if full[:cut] in modules:
            return full[:cut], (full[cut] if cut < len(full) else "")
    return None


def rust_edges(src: pathlib.Path, problems: list[str]) -> dict[pathlib.Path, dict[pathlib.Path, set[str]]]:
    modules = rust_modules(src)
    edges: dict[pathlib.Path, dict[pathlib.Path, set[str]]] = defaultdict(lambda: defaultdict(set))
    for here, path in modules.items():
        code = rust_code(path)
        paths = [(m.group(1), m.group(2)) for m in RUST_PATH.finditer(code)]
        for group in RUST_GROUP.finditer(code):
            for item in group.group(3).split(","):
                item = item.strip().split(" as ")[0].strip()
                if item and item != "self":
                    paths.append((group.group(1), group.group(2) + "::" + item.replace("::{", "::").strip("{} ")))
        # `super::` inside an inline module (`mod ctrl_c { ... }`) names this file's own items.
        own = set(OWN_ITEM.findall(code))
        for root, tail in paths:
            segments = [p for p in tail.split("::") if p]
            if root == "super" and segments and segments[0] in own:
                continue
            target = resolve(modules, here, root, segments)
            if target is None:
                continue
            module, name = target
            if module == here:
                continue
            if module == ():
                problems.append(f"{path.relative_to(ROOT)} takes {name} from the crate root: name its own module")
                continue
            if module == here[: len(module)]:
                continue  # a child's use of its own parent (which declares and re-exports it)
            edges[path][modules[module]].add(name or "(module)")
    return edges


def python_edges(package: pathlib.Path) -> dict[pathlib.Path, dict[pathlib.Path, set[str]]]:
    files = {p.relative_to(package.parent).with_suffix("").parts: p for p in package.rglob("*.py")}
    files = {(k[:-1] if k[-1] == "__init__" else k): v for k, v in files.items()}
    edges: dict[pathlib.Path, dict[pathlib.Path, set[str]]] = defaultdict(lambda: defaultdict(set))
    for here, path in files.items():
        is_package = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[tuple[tuple[str, ...], list[str]]] = []
            if isinstance(node, ast.ImportFrom):
                base = here if is_package else here[:-1]
                base = base[: len(base) - (node.level - 1)] if node.level else ()
                mod = base + tuple((node.module or "").split(".")) if node.module else base
                targets = [(mod, [a.name for a in node.names])]
            elif isinstance(node, ast.Import):
                targets = [(tuple(a.name.split(".")), []) for a in node.names]
            for mod, names in targets:
                for name in names or [""]:
                    candidate = mod + (name,) if name and mod + (name,) in files else mod
                    if candidate in files and files[candidate] != path and candidate != here[: len(candidate)]:
                        edges[path][files[candidate]].add(name or ".".join(mod))
    return edges


def circles(edges) -> list[list[pathlib.Path]]:
    """Strongly connected components of more than one node (Tarjan)."""
    index: dict[pathlib.Path, int] = {}
    low: dict[pathlib.Path, int] = {}
    stack: list[pathlib.Path] = []
    found = []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in edges.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10_000)
    for v in list(edges):
        if v not in index:
            visit(v)
    return found


def main() -> int:
    problems: list[str] = []
    graphs = [rust_edges(ROOT / "src", problems)]
    if (ROOT / "blender_addon").is_dir():
        graphs.append(python_edges(ROOT / "blender_addon"))
    for edges in graphs:
        for component in circles(edges):
            members = set(component)
            problems.append("circle: " + ", ".join(str(p.relative_to(ROOT)) for p in component))
            for a in component:
                for b, names in sorted(edges[a].items()):
                    if b in members:
                        problems.append(f"  {a.relative_to(ROOT)} -> {b.relative_to(ROOT)}: {', '.join(sorted(names))}")
    for line in problems:
        print(line)
    if problems:
        return 1
    print("imports: one-way")
    return 0


if __name__ == "__main__":
    sys.exit(main())
