#!/usr/bin/env bash
# The main job: installs dependencies, builds rigidtouch and runs the demo on the built-in
# simulated device. Usage: bash scripts/demo.sh [output directory, default out/]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
# the same configuration as scripts/test.sh's release build, so that the tests later reuse every
# object built here instead of rebuilding them with other options; only the tool is built now
python=/usr/bin/python3
[ -x "$python" ] || python=$(command -v python3)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRIGIDTOUCH_WERROR=ON -DRIGIDTOUCH_BUILD_TESTS=ON \
  -DRIGIDTOUCH_BUILD_BENCHMARKS=ON -DRIGIDTOUCH_BUILD_PYTHON=ON -DPython3_EXECUTABLE="$python" \
  >/dev/null
cmake --build build -j"$jobs" --target rigidtouch_cli
out="${1:-out}"
# the method's three walls and pure penalty, tapped three times at 0.1 m/s by the simulated hand
# on the simulated omega.3 (12 N, 5000 N/m): a table, traces, and figures in $out/
./build/rigidtouch tap --compare-walls --device omega3 --speed 0.1 --taps 3 --out-dir "$out"
