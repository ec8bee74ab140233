#!/usr/bin/env python3
"""Fails when two source files that may share a unity-build batch give an internal name to two
things: a function, constant, type or alias at the top of an anonymous namespace, or a `static`
function. In one batch such names clash, or worse, two overloads from different files meet and a
call silently takes the other file's (docs/testing.md, "Unity builds"). The groups: each folder
of tests/, and src/ with apps/ and bench/ (the libraries' folders share batches in their stage
library). Usage: python3 scripts/check-unity-names.py [ROOT]; exit 1 lists each clash."""

import re
import sys
from collections import defaultdict
from pathlib import Path

# a definition at column 0: `[constexpr|const|inline|static ...] TYPE NAME(` or `NAME =`/`{`,
# `struct|class|enum [class] NAME`, or `using NAME =`
DEFINITION = re.compile(
    r"^(?=\w)(?:template\s*<[^>]*>\s*)?(?:(?:constexpr|const|inline|static|thread_local)\s+)*"
    r"(?:(?:struct|class|enum class|enum)\s+(?P<type>\w+)|using\s+(?P<alias>\w+)\s*="
    r"|[\w:<>,\s*&]+?[\s*&](?P<name>\w+)\s*(?:\(|=|\{|;))")


def internal_names(path):
    """The names defined at the top of the file's anonymous namespaces, and its static functions."""
    names = set()
    depth = 0  # nesting of anonymous namespaces
    for line in path.read_text(errors="replace").splitlines():
        if line.startswith("namespace {"):
            depth += 1
            continue
        if depth and line.rstrip() == "}  // namespace":
            depth -= 1
            continue
        match = DEFINITION.match(line)
        if not match or line.startswith(("return", "else", "namespace ")):
            continue
        name = match.group("type") or match.group("alias") or match.group("name")
        if name in ("operator", "main"):
            continue
        if depth or line.startswith("static "):
            names.add(name)
    return names


def groups(root):
    yield "src, apps, bench", [*root.glob("src/*/*.cc"), *root.glob("apps/*/*.cc"),
                               *root.glob("bench/*.cc")]
    for area in sorted(p for p in (root / "tests").iterdir() if p.is_dir()):
        files = sorted(area.glob("*_test.cc"))
        if files:
            yield f"tests/{area.name}", files


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent)
    clashes = 0
    for group, files in groups(root):
        owners = defaultdict(list)
        for path in sorted(files):
            for name in internal_names(path):
                owners[name].append(path.relative_to(root).as_posix())
        for name, paths in sorted(owners.items()):
            if len(paths) > 1:
                clashes += 1
                print(f"check-unity-names: {group}: '{name}' is defined in {', '.join(paths)}")
    if clashes:
        print(f"check-unity-names: {clashes} internal names defined twice; give each its own name "
              "or share one definition in a header", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
