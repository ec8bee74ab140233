#!/usr/bin/env bash
# Builds rigidtouch with warnings as errors and runs every test; then rebuilds the unit tests with
# AddressSanitizer + UndefinedBehaviorSanitizer and runs them again. `--quick` skips the
# sanitizer pass. Usage: bash scripts/test.sh [--quick]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)

echo "== format check"
files=$(git ls-files '*.h' '*.cc' 2>/dev/null || true)
if [ -n "$files" ]; then clang-format --dry-run --Werror $files; fi

echo "== release build, -Wall -Wextra -Werror"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRIGIDTOUCH_WERROR=ON -DRIGIDTOUCH_BUILD_TESTS=ON \
  -DRIGIDTOUCH_BUILD_BENCHMARKS=ON
cmake --build build -j"$jobs"
(cd build && ctest --output-on-failure -j"$jobs")

echo "== install, and find_package(rigidtouch) from another project"
prefix="$(pwd)/build/install-check"
cmake --install build --prefix "$prefix" >/dev/null
cmake -S tests/install -B build/consumer -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build build/consumer -j"$jobs" >/dev/null
./build/consumer/consumer scenes/tap.xml

if [ "${1:-}" != "--quick" ]; then
  echo "== AddressSanitizer + UndefinedBehaviorSanitizer over the unit tests"
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRIGIDTOUCH_WERROR=ON \
    -DRIGIDTOUCH_SANITIZE=ON -DRIGIDTOUCH_BUILD_TESTS=ON
  cmake --build build-asan -j"$jobs"
  (cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --output-on-failure -j"$jobs" -LE no_sanitize)
fi
