#!/usr/bin/env python3
"""Imports point down: the kernel's modules stand on floors (ARCHITECTURE.md, "Floors"), and a
module may use the modules of the floors below its own, never one above it nor another module
of its own floor. Every `crate::name` path in the code of src/ (comments and doc comments are
not read; a name re-exported at the crate root counts as the module that defines it) is
checked against the order below. The pairs in .ci/floors-allowed.txt are the known exceptions
still to be removed: a new one fails, and so does a listed one that no longer occurs (delete
its line). Run from the repository root: python3 .ci/floors.py"""
import pathlib
import re
import sys

# Top to bottom; one floor a line, the modules that share it.
FLOORS = [
    ["world"],
    ["phases"],
    ["effects", "boundary"],
    ["material"],
    ["simd"],
    ["grid"],
    ["particles"],
    ["storage"],
    ["layout"],
    ["cut"],
    ["shape"],
    ["def"],
    ["math"],
    ["num"],
    ["tasks"],
    ["error"],
]
LEVEL = {m: len(FLOORS) - i for i, floor in enumerate(FLOORS) for m in floor}

src = pathlib.Path("src")
lib = (src / "lib.rs").read_text()
# Names the crate root re-exports: `pub use module::{A, B};` or `pub use module::A;`.
reexport = {}
for m in re.finditer(r"pub use (\w+)::(\{[^}]*\}|\w+);", lib):
    module, names = m.group(1), m.group(2)
    for name in re.findall(r"\w+", names):
        reexport[name] = module


def module_of(path):
    rel = path.relative_to(src)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def code_lines(text):
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("//"):
            continue
        yield line.split("//", 1)[0] if "//" in line and '"' not in line else line


found = set()
for path in sorted(src.rglob("*.rs")):
    here = module_of(path)
    if here == "lib":
        continue
    if here not in LEVEL:
        sys.exit(f"floors: {path} is in module `{here}`, which no floor names (add it)")
    code = "\n".join(code_lines(path.read_text()))
    names = re.findall(r"\bcrate::(\w+)", code)
    for group in re.findall(r"\bcrate::\{([^}]*)\}", code):
        names += re.findall(r"(?:^|,)\s*(\w+)", group)
    if True:
        for name in names:
            target = name if name in LEVEL else reexport.get(name)
            if target is None or target == here:
                continue
            if target not in LEVEL:
                sys.exit(f"floors: `crate::{name}` in {path}: module `{target}` has no floor")
            if LEVEL[target] >= LEVEL[here]:
                found.add((str(path), target))



def files_circles():
    """Circles between the files of one module (a directory under src): file A names file B
    when its code says `super::b`, `crate::module::b` or, in mod.rs, `b::`, or names an item
    that mod.rs re-exports from b (`pub(crate) use b::Item;`); an item mod.rs defines makes
    an edge to mod.rs. mod.rs's own `mod` and re-export lines are declarations, not uses."""
    circles = []
    for directory in sorted(p for p in src.iterdir() if p.is_dir()):
        files = {f.stem: f for f in directory.glob("*.rs")}
        module = directory.name
        top = files.get("mod")
        exported = {}
        if top is not None:
            for m in re.finditer(r"pub(?:\(crate\))? use (\w+)::(\{[^}]*\}|\w+);", top.read_text()):
                if m.group(1) in files:
                    for name in re.findall(r"\w+", m.group(2)):
                        exported[name] = m.group(1)
        edges = {stem: set() for stem in files}

        def target(name):
            if name in files:
                return name
            return exported.get(name, "mod")

        for stem, path in files.items():
            lines = code_lines(path.read_text())
            if stem == "mod":
                lines = (
                    line
                    for line in lines
                    if not re.match(r"\s*(pub(\(crate\))? )?(mod|use) ", line)
                )
            code = "\n".join(lines)
            names = re.findall(r"\bsuper::(\w+)", code)
            for group in re.findall(r"\bsuper::\{([^}]*)\}", code):
                names += re.findall(r"(?:^|,)\s*(\w+)", group)
            names += re.findall(rf"\bcrate::{module}::(\w+)", code)
            if stem == "mod":
                names += [n for n in re.findall(r"\b(\w+)::", code) if n in files]
            for name in names:
                to = target(name)
                if to != stem and to in files:
                    edges[stem].add(to)
        # Tarjan's strongly connected components: a component of two files or more is a circle.
        index, low, stack, on, counter = {}, {}, [], set(), [0]

        def visit(v):
            index[v] = low[v] = counter[0]
            counter[0] += 1
            stack.append(v)
            on.add(v)
            for w in sorted(edges[v]):
                if w not in index:
                    visit(w)
                    low[v] = min(low[v], low[w])
                elif w in on:
                    low[v] = min(low[v], index[w])
            if low[v] == index[v]:
                component = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    component.append(w)
                    if w == v:
                        break
                if len(component) > 1:
                    circles.append(f"src/{module}: " + ", ".join(sorted(component)))

        for v in sorted(edges):
            if v not in index:
                visit(v)
    return circles


circles = files_circles()
for circle in circles:
    print(f"floors: a circle between the files of {circle}")

allowed_file = pathlib.Path(".ci/floors-allowed.txt")
allowed = set()
for line in allowed_file.read_text().splitlines():
    line = line.split("#", 1)[0].strip()
    if line:
        path, target = (s.strip() for s in line.split("->"))
        allowed.add((path, target))

new = sorted(found - allowed)
stale = sorted(allowed - found)
for path, target in new:
    print(f"floors: {path} uses `{target}`, on its own floor or above")
for path, target in stale:
    print(f"floors: {path} -> {target} is allowed but no longer occurs: remove the line")
print(f"floors: {len(found)} known exceptions, {len(new)} new, {len(stale)} stale")
print(f"floors: {len(circles)} circles between the files of a module")
sys.exit(1 if new or stale or circles else 0)
