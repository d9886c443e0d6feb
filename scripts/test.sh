#!/usr/bin/env bash
# Installs what is missing, builds everything and runs the whole test suite.
#   scripts/test.sh                 release build in build/
#   scripts/test.sh --sanitize      AddressSanitizer + UBSan build in build-asan/
set -euo pipefail
cd "$(dirname "$0")/.."
# The whole suite: also the optional packages whose tests are otherwise skipped.
./scripts/setup.sh --slurm --plots --eval --fuzz --gl --waves --games --supertuxkart
dir=build
args=(-DCMAKE_BUILD_TYPE=Release)
select=()
if [ "${1:-}" = "--sanitize" ]; then
  dir=build-asan
  # -O1 with line tables only: what ASan's reports need (file and line of each
  # frame), at about half the compile time of -O2 -g, which would be most of CI's.
  args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DRBCD_SANITIZE=ON
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
  # Leak detection stays on. ASan notes once per process that SystemC switched
  # stacks under an exception (a remark, not an error; the CLI tests discard
  # exactly that note); any real error aborts the test.
  export ASAN_OPTIONS="abort_on_error=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  # The Python tests of Python code run once, in the release build
  # (cmake/pytest.cmake, RELEASE_ONLY, says which and why).
  select=(--label-exclude "release_only")
fi
cmake -S . -B "$dir" -G Ninja "${args[@]}" >/dev/null
cmake --build "$dir"
ctest --test-dir "$dir" -j"$(nproc)" --output-on-failure "${select[@]}"
