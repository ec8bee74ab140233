#!/usr/bin/env bash
# Lists every function in the tracked .cc files of src/, apps/ and python/ whose body is longer
# than the limit (default 120 lines) and exits 1 if there is one. A function starts at a line in
# column 0 that is not a comment, preprocessor line, namespace or type declaration, and ends with
# `{` (after a one- or multi-line signature); it ends at the next `}` in column 0. clang-format
# keeps both braces there for every free function and out-of-class member definition; a member
# function defined inside its class body (indented) is not checked.
# Usage: bash scripts/check-function-length.sh [max-lines]
set -euo pipefail
cd "$(dirname "$0")/.."
max=${1:-120}
files=$(git ls-files 'src/*.cc' 'apps/*.cc' 'python/*.cc')
[ -n "$files" ] || exit 0
# shellcheck disable=SC2086
awk -v max="$max" '
  FNR == 1 { in_body = 0; in_sig = 0 }
  in_body {
    if ($0 ~ /^}/) {
      n = FNR - start + 1
      if (n > max) { printf "%s:%d: %s: %d lines (limit %d)\n", FILENAME, start, name, n, max; bad++ }
      in_body = 0
    }
    next
  }
  # a signature starts in column 0 with a name, type or template; skip comments, preprocessor
  # lines, braces, namespaces, types, and `using`/`extern "C"` lines
  !in_sig && /^[A-Za-z_]/ && !/^(namespace|class|struct|enum|union|using|typedef|extern|static_assert)[ {;(]/ {
    in_sig = 1; start = FNR; sig = ""
  }
  in_sig {
    code = $0; sub(/[ \t]*\/\/.*/, "", code)  # a trailing comment
    sig = sig " " code
    if (code ~ /;[ \t]*$/) { in_sig = 0; next }  # a declaration or variable
    if (code ~ /\{[ \t]*$/) {
      in_sig = 0
      # a one-line initializer such as `const X y = {` is not a function
      if (sig ~ /=[ \t]*[A-Za-z_:<>]*[ \t]*\{[ \t]*$/) next
      in_body = 1
      name = sig; sub(/\(.*/, "", name); sub(/.*[ *&>]/, "", name)
    }
    next
  }
  END { exit bad > 0 ? 1 : 0 }
' $files
