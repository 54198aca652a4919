#!/usr/bin/env python3
"""The accuracy report measured the kernel as it is: results/accuracy_cost/README.md names the
SHA-256 of the kernel source it measured (every file under src/ and Cargo.toml), and this
check computes the same digest of the source now (examples/accuracy_cost/source.rs says
how: the files in path order, each as its path, its length and its contents with CR LF read
as LF). A change to the kernel therefore ends with the report written again.

Run from the repository root: python3 .ci/accuracy_source.py [--print] [REPORT]
(--print: only print the digest of the source now)."""
import hashlib
import pathlib
import re
import sys

REGENERATE = "cargo run --release --example accuracy_cost"


def kernel_source_hash(root=pathlib.Path(".")):
    files = ["Cargo.toml"] + [p.relative_to(root).as_posix() for p in (root / "src").rglob("*")
                              if p.is_file()]
    digest = hashlib.sha256()
    for name in sorted(files, key=lambda f: f.encode()):
        text = (root / name).read_bytes().replace(b"\r\n", b"\n")
        digest.update(f"{name}\n{len(text)}\n".encode() + text)
    return digest.hexdigest()


def main():
    args = sys.argv[1:]
    now = kernel_source_hash()
    if args == ["--print"]:
        print(now)
        return 0
    report = pathlib.Path(args[0] if args else "results/accuracy_cost/README.md")
    found = re.search(r"kernel source sha256 `([0-9a-f]{64})`", report.read_text())
    if not found:
        print(f"accuracy report: {report} names no kernel source it measured (no line "
              f"\"kernel source sha256 `<64 hex digits>`\"): write it again with "
              f"`{REGENERATE}` (about 200 s on an idle machine) and commit it")
        return 1
    if found.group(1) != now:
        print(f"accuracy report: {report} measured kernel source {found.group(1)[:16]}..., "
              f"the kernel source (src/, Cargo.toml) is now {now[:16]}...: write the report "
              f"again with `{REGENERATE}` (about 200 s on an idle machine) and commit it")
        return 1
    print(f"accuracy report: measured this kernel source ({now[:16]}...)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
