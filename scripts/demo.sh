#!/usr/bin/env bash
# The main job: installs dependencies, builds rigidtouch and runs the demo on the built-in
# simulated device. Usage: bash scripts/demo.sh [output directory, default out/]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRIGIDTOUCH_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$jobs" --target rigidtouch_cli
out="${1:-out}"
mkdir -p "$out"
# the tool (5 mm sphere, 0.1 kg) dropped 1 mm onto a wall and pressed with 2 N, one run per
# renderer: pure penalty, single impulse (wall 0), impulse train at 250 Hz (wall 1)
for renderer in penalty impulse train; do
  ./build/rigidtouch simulate --scene scenes/tap.xml --tool-force 0 0 -2 --steps 300 \
    --renderer "$renderer" --json > "$out/simulate_$renderer.json"
  ./build/rigidtouch simulate --scene scenes/tap.xml --tool-force 0 0 -2 --steps 300 \
    --renderer "$renderer" | head -3
done
echo "JSON results in $out/"
