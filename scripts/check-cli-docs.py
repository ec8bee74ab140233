#!/usr/bin/env python3
"""The command line's help against the docs: every flag of every subcommand is in docs/cli.md's
synopsis entry for that subcommand, and every flag the README and docs/ write after
`rigidtouch SUBCOMMAND` exists for that subcommand. Exits 1 listing what disagrees, 0 otherwise.

usage: check-cli-docs.py --cli build/rigidtouch [--root .]
"""

import argparse
import pathlib
import re
import subprocess
import sys

FLAG = re.compile(r"--[a-z][a-z0-9-]*")
# flags every subcommand has (CLI11's own)
ALWAYS = {"--help"}


def run_help(cli, path):
    out = subprocess.run([cli, *path, "--help"], capture_output=True, text=True, check=False)
    if out.returncode != 0:
        sys.exit(f"check-cli-docs: `{' '.join(['rigidtouch', *path, '--help'])}` exited "
                 f"{out.returncode}: {out.stderr.strip()}")
    return out.stdout


def parse_help(text):
    """(flags, subcommands) of one help page."""
    flags, subcommands, section = set(), [], None
    for line in text.splitlines():
        if line.endswith(":") and not line.startswith(" "):
            section = line[:-1]
            continue
        if section == "Options":
            m = re.match(r"\s+(?:-\w,)?(--[a-z][a-z0-9-]*)", line)
            if m:
                flags.add(m.group(1))
                # aliases: -x,--long,--other
                head = line.split()[0] if line.split() else ""
                flags.update(f for f in FLAG.findall(head))
        elif section == "Subcommands":
            m = re.match(r"  ([a-z][a-z0-9-]*)\s", line + " ")
            if m:
                subcommands.append(m.group(1))
    return flags, subcommands


def command_tree(cli):
    """{('tap',): flags, ('study', 'run'): flags, ...} for every subcommand, nested ones too."""
    tree = {}
    pending = [()]
    while pending:
        path = pending.pop()
        flags, subs = parse_help(run_help(cli, list(path)))
        if path:
            tree[path] = flags
        pending.extend(path + (s,) for s in subs)
    return tree


def command_at(words, tree):
    """The longest subcommand path that `words` starts with, or None."""
    best = None
    for n in range(1, len(words) + 1):
        if tuple(words[:n]) in tree:
            best = tuple(words[:n])
    return best


def synopsis_entries(cli_md):
    """The text of each entry of docs/cli.md's Synopsis block, with `[SCENE FLAGS]` replaced by
    the block's own definition of it (`SCENE FLAGS = ...`)."""
    text = cli_md.read_text()
    start = text.index("## Synopsis")
    end = text.index("\n## ", start + 1)
    entries, current, macro = [], None, None
    for line in text[start:end].splitlines():
        m = re.match(r"    (rigidtouch|SCENE FLAGS =) (.*)", line)
        if m:
            current = [m.group(2)]
            if m.group(1) == "rigidtouch":
                entries.append(current)
            else:
                macro = current
        elif current is not None and line.startswith("     "):
            current.append(line)
        else:
            current = None
    scene_flags = " ".join(macro) if macro else ""
    return [" ".join(e).replace("[SCENE FLAGS]", scene_flags) for e in entries]


def command_segments(text):
    """Every `rigidtouch WORDS...` written in `text`, cut where the command ends: a backtick, the
    end of a line not continued with a backslash, or a shell pipe or list into another command."""
    text = text.replace("\\\n", " ")
    for m in re.finditer(r"(?:^|[\s`(/])rigidtouch ((?:[^`\n])*)", text):
        segment = m.group(1)
        segment = re.split(r" (?:\|\||&&|;|\|) (?=[a-zA-Z./])", segment)[0]
        yield segment


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", required=True, help="the rigidtouch binary")
    parser.add_argument("--root", default=str(pathlib.Path(__file__).resolve().parent.parent))
    args = parser.parse_args()
    root = pathlib.Path(args.root)
    tree = command_tree(args.cli)
    problems = []

    # 1. the synopsis: an entry per subcommand that takes flags, holding every one of them
    documented = {}
    for entry in synopsis_entries(root / "docs" / "cli.md"):
        words = entry.split()
        path = command_at(words, tree)
        if path is None:
            problems.append(f"docs/cli.md synopsis: no subcommand '{words[0]}'")
            continue
        documented.setdefault(path, set()).update(FLAG.findall(entry))
    for path, flags in sorted(tree.items()):
        is_group = any(p[:len(path)] == path and len(p) > len(path) for p in tree)
        if is_group and flags <= ALWAYS:
            continue
        missing = sorted(flags - ALWAYS - documented.get(path, set()))
        if path not in documented:
            problems.append(f"docs/cli.md synopsis: no entry for `rigidtouch {' '.join(path)}`")
        elif missing:
            problems.append(f"docs/cli.md synopsis of `rigidtouch {' '.join(path)}` lacks "
                            f"{', '.join(missing)}")

    # 2. every flag written after a subcommand in the README and docs/ exists for it
    pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    for page in pages:
        for segment in command_segments(page.read_text()):
            words = segment.split()
            path = command_at(words, tree)
            if path is None:
                continue
            for flag in FLAG.findall(" ".join(words[len(path):])):
                if flag not in tree[path] and flag not in ALWAYS:
                    problems.append(f"{page.relative_to(root)}: `rigidtouch {' '.join(path)}` "
                                    f"has no flag {flag} (in: rigidtouch {segment.strip()[:90]})")

    for p in problems:
        print(f"check-cli-docs: {p}")
    if problems:
        print(f"check-cli-docs: {len(problems)} disagreement(s) between the help and the docs")
        return 1
    print(f"check-cli-docs: {len(tree)} subcommands, every flag documented and every documented "
          "flag real")
    return 0


if __name__ == "__main__":
    sys.exit(main())
