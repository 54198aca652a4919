#!/usr/bin/env python3
"""The docs' figures come from commands in the repository, and the commands exist.

- Every example a doc runs (`--example NAME`) is an example of one of the workspace's
  packages, and every script, source or C file a doc names by path exists (relative to the
  repository or to the doc).
- Every section of benches/PERFORMANCE.md that holds a table of figures names the command
  that measures them (`cargo ...`, `bash ...`, `target/...`, `python ...`), so a reader can
  run it again.

Run from the repository root: python3 .ci/docs.py"""
import pathlib
import re
import sys

DOCS = ["README.md", "ARCHITECTURE.md", "ffi/README.md", "tests/README.md", "python/README.md"]
DOCS += [str(p) for p in sorted(pathlib.Path("benches").glob("*.md"))]
DOCS += [str(p) for p in sorted(pathlib.Path("docs").glob("*.md"))]
PACKAGES = [".", "ffi", "output", "rayon", "viewer"]

failed = []
examples = set()
for package in PACKAGES:
    folder = pathlib.Path(package) / "examples"
    if folder.is_dir():
        examples |= {p.stem for p in folder.glob("*.rs")}
        examples |= {p.name for p in folder.iterdir() if (p / "main.rs").exists()}

for doc in DOCS:
    path = pathlib.Path(doc)
    if not path.exists():
        continue
    text = path.read_text()
    for name in re.findall(r"--example ([A-Za-z0-9_]+)", text):
        if name not in examples:
            failed.append(f"{doc}: `--example {name}` is no example of the workspace")
    for file in set(re.findall(r"(?<![\w/.-])((?:[\w.-]+/)+[\w.-]+\.(?:sh|py|rs|c|cpp|h|toml))(?!\w)", text)):
        bases = [pathlib.Path("."), path.parent, pathlib.Path("src")]
        if not any((base / file).exists() for base in bases):
            failed.append(f"{doc}: `{file}` does not exist")

performance = pathlib.Path("benches/PERFORMANCE.md").read_text()
command = re.compile(r"`(cargo |bash |target/|perf |valgrind |MPM_GIMP_|python3? )[^`]*`")
sections = re.split(r"\n(?=#{2,3} )", performance)
tables = 0
for section in sections:
    title = section.splitlines()[0]
    # The decisions table cites the figures of the sections above it.
    if "|---" not in section or title.strip("# ") == "Decisions":
        continue
    tables += 1
    if not command.search(section):
        failed.append(f"benches/PERFORMANCE.md, {title!r}: a table with no command that measures it")

print(f"docs: {len(DOCS)} read, {len(examples)} examples known, {tables} sections of figures")
for f in failed:
    print(f"docs: {f}")
sys.exit(1 if failed else 0)
