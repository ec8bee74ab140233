#!/usr/bin/env bash
# Runs the README's commands as a newcomer would: every ```sh block of README.md, in order, on a
# machine with the packages installed, in a checkout of this commit that nothing has changed. The
# block that runs scripts/test.sh is skipped: it is the command that runs this check. A block whose
# command opens the viewer runs under xvfb-run when there is no display. Exits 1 naming the README
# line of the first block that fails.
#
# Where: in this checkout when it is clean (`git status --porcelain` empty: CI's fresh clone, after
# scripts/test.sh has built and tested it), else in a fresh clone of the last commit (uncommitted
# changes are not in it). In place, the main job's build finds the release build the test command
# made from scratch with the same configuration (scripts/demo.sh configures as scripts/test.sh
# does), so the full gate does not compile it a second time; --fresh-clone always clones.
# Usage: bash scripts/check-readme.sh [--fresh-clone]
set -euo pipefail
cd "$(dirname "$0")/.."
fresh=0
case "${1:-}" in
  "") ;;
  --fresh-clone) fresh=1 ;;
  *)
    echo "check-readme: error: unknown option '$1' (usage: bash scripts/check-readme.sh [--fresh-clone])" >&2
    exit 2
    ;;
esac
root=$(pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/rigidtouch-readme.XXXXXX")
trap 'rm -rf "$work"' EXIT
if [ "$fresh" = 0 ] && [ -z "$(git status --porcelain)" ]; then
  echo "-- in this checkout, clean at $(git rev-parse --short HEAD)"
else
  echo "-- in a fresh clone of $(git rev-parse --short HEAD)"
  git clone -q "$root" "$work/clone"
  cd "$work/clone"
fi

# one file per block: blocks/<README line of its fence>.sh
mkdir "$work/blocks"
awk -v dir="$work/blocks" '
  /^```sh[[:space:]]*$/ { inside = 1; file = sprintf("%s/%05d.sh", dir, NR); next }
  /^```/ && inside { inside = 0; close(file); next }
  inside { print > file }
' README.md
blocks=$(ls "$work/blocks")
[ -n "$blocks" ] || {
  echo "check-readme: error: README.md has no \`\`\`sh block" >&2
  exit 1
}
ran=0
skipped=0
for block in $blocks; do
  line=$((10#${block%.sh}))
  if grep -q 'scripts/test\.sh' "$work/blocks/$block"; then
    echo "-- README.md:$line: skipped (the test command runs this check)"
    skipped=$((skipped + 1))
    continue
  fi
  echo "-- README.md:$line"
  sed 's/^/   $ /' "$work/blocks/$block"
  wrap=()
  if grep -q 'rigidtouch view' "$work/blocks/$block" && [ -z "${DISPLAY:-}" ] &&
    ! grep -q 'xvfb-run' "$work/blocks/$block"; then
    wrap=(xvfb-run -a)
  fi
  start_s=$(date +%s)
  if ! "${wrap[@]}" bash -euo pipefail "$work/blocks/$block" >"$work/output" 2>&1; then
    tail -n 40 "$work/output"
    echo "check-readme: error: the block at README.md:$line failed (its output's last lines above)" >&2
    exit 1
  fi
  tail -n 3 "$work/output" | sed 's/^/   | /'
  echo "   ($(($(date +%s) - start_s)) s)"
  ran=$((ran + 1))
done
echo "check-readme: $ran blocks ran, $skipped skipped"
