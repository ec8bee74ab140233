#!/usr/bin/env python3
"""Checks the include graph of src/ against the floors of src/layers.txt.

Every `#include "folder/file.h"` of a file in src/<folder>/ must name its own folder, a folder on a
lower floor, or the public API (rigidtouch/, include/); and no chain of includes between files may
come back to where it started. Exits 1 naming each offending include, 0 when there is none.

    python3 scripts/check-layers.py [--root DIR]
"""
import argparse
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)
PUBLIC = "rigidtouch"


def read_floors(path):
    """{folder: floor number} from the layers file, lowest floor 0."""
    floors = {}
    number = 0
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].split()
        if not line:
            continue
        for folder in line:
            if folder in floors:
                sys.exit(f"{path}: folder {folder} is on two floors")
            floors[folder] = number
        number += 1
    return floors


def sources(src):
    return sorted(p for p in src.rglob("*") if p.suffix in (".h", ".cc") and p.is_file())


def check_floors(src, floors, files):
    problems = []
    for path in files:
        rel = path.relative_to(src)
        folder = rel.parts[0]
        if len(rel.parts) < 2:
            continue
        if folder not in floors:
            problems.append(f"src/{rel}: folder {folder}/ is on no floor of src/layers.txt")
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            target = match.group(1).split("/")[0]
            if "/" not in match.group(1) or target == folder or target == PUBLIC:
                continue
            if target not in floors:
                problems.append(f"src/{rel}:{number}: includes \"{match.group(1)}\": "
                                f"{target}/ is on no floor of src/layers.txt")
            elif floors[target] >= floors[folder]:
                where = "the same floor as" if floors[target] == floors[folder] else "above"
                problems.append(f"src/{rel}:{number}: includes \"{match.group(1)}\": "
                                f"{target}/ is {where} {folder}/")
    return problems


def check_cycles(src, files):
    """Include cycles between files of src/ (within a folder the floors cannot see them)."""
    graph = {}
    for path in files:
        rel = str(path.relative_to(src))
        graph[rel] = [inc for inc in INCLUDE.findall(path.read_text()) if (src / inc).is_file()]
    problems, state = [], {}

    def visit(node, stack):
        state[node] = "open"
        stack.append(node)
        for nxt in graph.get(node, []):
            if state.get(nxt) == "open":
                cycle = stack[stack.index(nxt):] + [nxt]
                problems.append("include cycle: " + " -> ".join("src/" + c for c in cycle))
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [])
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent,
                        type=pathlib.Path, help="the repository (default: this script's)")
    args = parser.parse_args()
    src = args.root / "src"
    floors = read_floors(src / "layers.txt")
    files = sources(src)
    problems = check_floors(src, floors, files) + check_cycles(src, files)
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        print(f"check-layers: {len(problems)} include(s) break the floors of src/layers.txt",
              file=sys.stderr)
        return 1
    print(f"check-layers: {len(files)} files of src/ include only their own folder and lower floors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
