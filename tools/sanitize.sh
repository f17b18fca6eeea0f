#!/usr/bin/env bash
# Builds everything with AddressSanitizer and UndefinedBehaviorSanitizer in ./build-asan (-O1) and
# runs the whole test suite there. It builds with clang (tools/setup.sh --tests installs it and its
# sanitizer runtimes): the same sources compile about a third faster than with GCC at -O1 with the
# sanitizers (generate_test.cpp: 49 s against 77 s of CPU), and the suite is then checked by a
# second compiler's warnings and checks as well as the Release build's GCC. Leak checking is off:
# OpenCASCADE, TBB and assimp keep process-lifetime singletons that LeakSanitizer would report on
# every test.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmake -S "$root" -B "$root/build-asan" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1" \
  -DCADSYNTH_SANITIZE=ON -DCADSYNTH_BUILD_BENCHMARKS=OFF
start=$SECONDS
cmake --build "$root/build-asan" --parallel "$(nproc)"
echo "sanitize: build took $((SECONDS - start)) s"
"$root/tools/seed_test_costs.sh" "$root/build-asan"
cd "$root/build-asan"
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# clang_format checks sources, not code; slurm_single_node starts daemons; the kubernetes_ checks
# are about manifests and schedulers' variables, whose code the gtest programs cover (all three
# run in tools/test.sh's Release tree); container_image builds its own Release image;
# cycles_comparison compares images against Blender's (the path tracer's code runs under the
# sanitizers in render_tests; at 128 samples a sanitized cadsynth would add minutes);
# verify_shipped_recipes, recipe_json_schema and docs_generated run the program on recipes and
# check files and text, which the Release tree does (verify_shipped_recipes took 335 s here, a
# fifth of the suite's CPU time, for code the gtest programs run under the sanitizers).
ctest --output-on-failure --parallel "$(nproc)" --timeout 1800 \
  -E "clang_format|slurm|kubernetes|container_image|cycles_comparison|verify_shipped_recipes|recipe_json_schema|docs_generated"
