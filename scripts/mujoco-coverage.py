#!/usr/bin/env python3
"""Runs MuJoCo's own articulated model and test files through `rigidtouch simulate --tool none`.

Issue 45 asks that MuJoCo 2.2.2's own articulated files (those without equality constraints,
tendons, fluid forces or composites) load and step 300 steps with finite state, at least 80 % of
them, and that the rest are refused with the element named (docs/scenes.md, "MuJoCo's own
models"). This script measures that. MuJoCo's files are not part of rigidtouch: pass a clone of
MuJoCo's repository (a work tree or a bare git directory),

    git clone https://github.com/deepmind/mujoco.git /some/where/mujoco
    python3 scripts/mujoco-coverage.py --mujoco /some/where/mujoco --ref 2.2.2 \
        --rigidtouch build/rigidtouch

The files of `model/` and `test/` at REF are extracted with `git archive` into a temporary
directory (so that <include>d files and meshes resolve), then:

* a file is *articulated* when its text, or the text of a file it <include>s, has a `<joint`
  element (a hinge, slide, ball, or a free joint spelled as <joint type="free">); files with only
  `<freejoint/>` bodies are free-body scenes, tried in docs/scenes.md's "MJCF files tried";
* files another file <include>s are parts, not models, and are left out;
* files with `<equality`, `<tendon`, `<composite`, or an `<option>` with a non-zero `density` or
  `viscosity` (fluid forces) are left out, as the issue says;
* each remaining file runs `simulate --scene F --tool none --steps 300 --json` and is classified:
  `stepped` (exit 0, `non_finite_state` null, every joint's position and velocity finite),
  `refused` (exit 2, the bad-input status, with a `rigidtouch: error:` line naming an element:
  `<...>`, `body '...'`, `geom '...'`), or `BUG` (anything else: a crash, a non-finite state, an
  error naming no element).

Prints a Markdown table and the summary; exits 1 when a file is a BUG.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tarfile
import tempfile

EXCLUDE = [("<equality", "equality"), ("<tendon", "tendon"), ("<composite", "composite")]


def git(repo, *args):
    """Runs git on a work tree or a bare directory."""
    gitdir = repo
    if os.path.isdir(os.path.join(repo, ".git")):
        gitdir = os.path.join(repo, ".git")
    return subprocess.run(["git", "--git-dir", gitdir, *args], check=True,
                          capture_output=True).stdout


def strip_comments(text):
    return re.sub(r"<!--.*?-->", "", text, flags=re.S)


def includes(text):
    return re.findall(r"<include\s[^>]*file\s*=\s*\"([^\"]+)\"", text)


def fluid(text):
    for option in re.findall(r"<option\b[^>]*>", text, flags=re.S):
        for name in ("density", "viscosity"):
            m = re.search(name + r"\s*=\s*\"([^\"]*)\"", option)
            if m and float(m.group(1).split()[0]) != 0.0:
                return True
    return False


def closure(root, path, seen=None):
    """The text of `path` and of every file it includes (relative to the including file)."""
    seen = seen if seen is not None else set()
    if path in seen or not os.path.isfile(os.path.join(root, path)):
        return ""
    seen.add(path)
    with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
        text = strip_comments(f.read())
    for inc in includes(text):
        text += closure(root, os.path.normpath(os.path.join(os.path.dirname(path), inc)), seen)
    return text


def select(root):
    """(articulated files to run, [(file, reason)] left out) under root's model/ and test/."""
    files = []
    for top in ("model", "test"):
        for d, _, names in os.walk(os.path.join(root, top)):
            files += [os.path.relpath(os.path.join(d, n), root) for n in names if n.endswith(".xml")]
    files.sort()
    included = set()
    for f in files:
        with open(os.path.join(root, f), encoding="utf-8", errors="replace") as fh:
            for inc in includes(strip_comments(fh.read())):
                included.add(os.path.normpath(os.path.join(os.path.dirname(f), inc)))
    run, left_out = [], []
    for f in files:
        text = closure(root, f)
        if "<joint" not in text:
            continue
        if f in included:
            left_out.append((f, "a part <include>d by another file"))
            continue
        reasons = [why for tag, why in EXCLUDE if tag in text]
        if fluid(text):
            reasons.append("fluid")
        if reasons:
            left_out.append((f, ", ".join(reasons)))
        else:
            run.append(f)
    return run, left_out


def finite(doc):
    for joint in doc.get("joints", []):
        for key in ("position", "velocity"):
            value = joint.get(key)
            values = value if isinstance(value, list) else [value]
            if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
                return False
    return True


def classify(binary, root, f, steps):
    cmd = [binary, "simulate", "--scene", os.path.join(root, f), "--tool", "none", "--steps",
           str(steps), "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    err = p.stderr.strip().replace(root + os.sep, "")
    doc = None
    try:
        doc = json.loads(p.stdout) if p.stdout.strip() else None
    except json.JSONDecodeError:
        pass
    if doc is not None and (doc.get("non_finite_state") is not None or not finite(doc)):
        return "BUG", "non-finite state: " + json.dumps(doc.get("non_finite_state"))
    if p.returncode == 0:
        if doc is None:
            return "BUG", "exit 0 but the output is not JSON"
        joints = len(doc.get("joints", []))
        warned = len([l for l in err.splitlines() if "rigidtouch: warning:" in l])
        return "stepped", f"{joints} joints, {warned} load warnings"
    line = next((l for l in err.splitlines() if "rigidtouch: error:" in l), "")
    names_element = re.search(r"<[a-z]+|body '|geom '|joint '|actuator '", line)
    if p.returncode == 2 and line and names_element:
        return "refused", line.split("rigidtouch: error:", 1)[1].strip()
    return "BUG", f"exit {p.returncode}: {err[-300:]}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mujoco", required=True, help="a clone of github.com/deepmind/mujoco")
    ap.add_argument("--ref", default="2.2.2", help="tag or commit (default 2.2.2)")
    ap.add_argument("--rigidtouch", default="build/rigidtouch", help="the CLI binary")
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    binary = os.path.abspath(args.rigidtouch)
    commit = git(args.mujoco, "rev-parse", args.ref + "^{commit}").decode().strip()
    with tempfile.TemporaryDirectory() as root:
        archive = os.path.join(root, "files.tar")
        with open(archive, "wb") as out:
            out.write(git(args.mujoco, "archive", "--format=tar", commit, "model", "test"))
        with tarfile.open(archive) as tar:
            tar.extractall(root)
        os.remove(archive)
        run, left_out = select(root)
        results = [(f, *classify(binary, root, f, args.steps)) for f in run]
    print(f"MuJoCo {args.ref} ({commit[:10]}): {len(run)} articulated files run, "
          f"{len(left_out)} left out\n")
    print("| File | Result | Detail |\n| --- | --- | --- |")
    for f, result, detail in results:
        print(f"| `{f}` | {result} | {detail.replace('|', '/')} |")
    for f, why in left_out:
        print(f"| `{f}` | left out | {why} |")
    counts = {k: sum(1 for r in results if r[1] == k) for k in ("stepped", "refused", "BUG")}
    share = 100.0 * counts["stepped"] / len(run) if run else 0.0
    print(f"\nstepped {counts['stepped']} of {len(run)} ({share:.0f} %), "
          f"refused {counts['refused']}, bugs {counts['BUG']}")
    return 1 if counts["BUG"] else 0


if __name__ == "__main__":
    sys.exit(main())
