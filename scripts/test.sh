#!/usr/bin/env bash
# The test command (docs/testing.md). By default: the format and function-length checks, the
# release build with -Wall -Wextra -Werror, every test but those labelled slow, the install check
# and the Python tests. `--full` (the CI gate) adds the slow tests, the README's commands as a
# newcomer runs them (scripts/check-readme.sh), the unit tests again under AddressSanitizer +
# UndefinedBehaviorSanitizer, the threaded tests under ThreadSanitizer and each libFuzzer harness
# for a bounded time.
# Usage: bash scripts/test.sh [--full]
set -euo pipefail
cd "$(dirname "$0")/.."
full=0
case "${1:-}" in
  "") ;;
  --full) full=1 ;;
  --quick) ;;  # the old spelling of the default run
  *)
    echo "scripts/test.sh: error: unknown option '$1' (usage: bash scripts/test.sh [--full])" >&2
    exit 2
    ;;
esac
[ $# -le 1 ] || {
  echo "scripts/test.sh: error: one option at most, got: $*" >&2
  exit 2
}
gate_start_s=$(date +%s)
bash scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
# prints how long the pass that started at $1 took
took() { echo "$2: $(($(date +%s) - $1)) s"; }

echo "== format, function-length and layering checks"
files=$(git ls-files '*.h' '*.cc' 2>/dev/null || true)
if [ -n "$files" ]; then clang-format --dry-run --Werror $files; fi
bash scripts/check-function-length.sh  # no function over 120 lines in src/, apps/, python/
python3 scripts/check-layers.py         # no include from a lower floor of src/ to a higher one
python3 scripts/check-unity-names.py    # no internal name defined twice in one unity batch

echo "== release build, -Wall -Wextra -Werror"
start_s=$(date +%s)
# the Python module is built for Debian's interpreter, where its packages are (not a pyenv's)
python=/usr/bin/python3
[ -x "$python" ] || python=$(command -v python3)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRIGIDTOUCH_WERROR=ON -DRIGIDTOUCH_BUILD_TESTS=ON \
  -DRIGIDTOUCH_BUILD_BENCHMARKS=ON -DRIGIDTOUCH_BUILD_PYTHON=ON -DPython3_EXECUTABLE="$python" \
  >/dev/null
cmake --build build -j"$jobs"
took "$start_s" "release build"
start_s=$(date +%s)
(cd build && ctest --output-on-failure -j"$jobs" -LE slow)
took "$start_s" "release tests"

echo "== install, and find_package(rigidtouch) from another project"
prefix="$(pwd)/build/install-check"
rm -rf "$prefix"
cmake --install build --prefix "$prefix" >/dev/null
cmake -S tests/install -B build/consumer -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
# the consumer and the OpenHaptics vendor bridge (against a stub of the HD API: never run)
cmake --build build/consumer -j"$jobs" >/dev/null
./build/consumer/consumer scenes/tap.xml
test -x build/consumer/openhaptics_bridge && echo "vendor bridge example built"

echo "== Python module: pytest against the installed package (docs/python.md)"
start_s=$(date +%s)
# set -e fails the script on any pytest status but 0, so also on 5 (no tests collected)
PYTHONPATH="$prefix/lib/python3/dist-packages" RIGIDTOUCH_CLI="$prefix/bin/rigidtouch" \
  "$python" -m pytest -q -p no:cacheprovider python/tests
PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" examples/python/worked_example.py \
  --out-dir build/python-example
took "$start_s" "Python pass"

# the default run ends here; --full prints this line too, so one run times both
took "$gate_start_s" "test command"
[ "$full" = 1 ] || exit 0

echo "== the slow tests (release build)"
start_s=$(date +%s)
(cd build && ctest --output-on-failure -j"$jobs" -L slow)
took "$start_s" "slow tests"

echo "== the README's commands after the main job (in this checkout when clean, else a fresh clone)"
start_s=$(date +%s)
bash scripts/check-readme.sh
took "$start_s" "README check"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer over the tests"
start_s=$(date +%s)
# clang at -O1 -g1 (line-number stacks): a third of gcc's -O2 -g build time, the tests as fast;
# the library, the CLI, the tests and the libFuzzer harnesses of tests/fuzz, which share the
# library compiled once (not the viewer, the benchmark or the Python module)
CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DRIGIDTOUCH_WERROR=ON \
  -DRIGIDTOUCH_SANITIZE=ON -DRIGIDTOUCH_BUILD_FUZZERS=ON -DRIGIDTOUCH_BUILD_TESTS=ON \
  -DRIGIDTOUCH_BUILD_VIEWER=OFF >/dev/null
cmake --build build-asan -j"$jobs"
took "$start_s" "AddressSanitizer build"
# the slow tests ran in the release pass above; each has a fast counterpart that runs here
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --output-on-failure -j"$jobs" -LE slow)
took "$start_s" "AddressSanitizer pass"

echo "== ThreadSanitizer over the threaded tests: loop, devices, the UDP bridge, the worker"
start_s=$(date +%s)
# clang at -O1 -g1 (line-number stacks in the reports) with its precompiled headers; only the
# test files that start threads are built
tsan_files="loop/*_test.cc;device/*_test.cc;cli/bridge_cli_test.cc;cli/fake_device_test.cc"
tsan_files+=";parallel/worker_test.cc"
CC=clang CXX=clang++ cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRIGIDTOUCH_WERROR=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DRIGIDTOUCH_SANITIZE_THREAD=ON \
  -DRIGIDTOUCH_BUILD_TESTS=ON -DRIGIDTOUCH_BUILD_VIEWER=OFF \
  "-DRIGIDTOUCH_TEST_FILES=$tsan_files" >/dev/null
cmake --build build-tsan -j"$jobs"
took "$start_s" "ThreadSanitizer build"
# -j1: the loop tests measure timing, and TSan slows every thread
(cd build-tsan && TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --output-on-failure -LE slow)
took "$start_s" "ThreadSanitizer pass"

echo "== libFuzzer: each harness of tests/fuzz from its seed corpus, bounded in time"
start_s=$(date +%s)
# built with ASan + UBSan in the AddressSanitizer pass above
fuzz_targets=$(ls tests/fuzz/*_fuzz.cc | xargs -n1 basename | sed 's/\.cc$//')
for target in $fuzz_targets; do
  name=${target%_fuzz}
  # new inputs go to a scratch folder, the committed seeds stay as they are; a crash leaves its
  # input in build-asan/fuzz/artifacts/ and fails the pass. A fixed mutation seed makes a run
  # repeatable (a crash here reproduces with the same seed); RIGIDTOUCH_FUZZ_SEED=0 (libFuzzer:
  # a random seed) and a larger RIGIDTOUCH_FUZZ_SECONDS explore further
  scratch="build-asan/fuzz/corpus/$name"
  mkdir -p "$scratch" build-asan/fuzz/artifacts
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "build-asan/tests/fuzz/$target" -max_total_time="${RIGIDTOUCH_FUZZ_SECONDS:-20}" \
    -seed="${RIGIDTOUCH_FUZZ_SEED:-1}" \
    -runs=2000000 -max_len=4096 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix=build-asan/fuzz/artifacts/"$name"- \
    "$scratch" "tests/fuzz/corpus/$name" 2>&1 | tail -n 12
done
took "$start_s" "fuzz pass"
took "$gate_start_s" "full gate"
