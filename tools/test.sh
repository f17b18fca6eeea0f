#!/usr/bin/env bash
# Installs what is missing, builds, runs the default job, and runs the whole test suite:
# - build/ (Release, GCC): the program, the Python module and the benchmarks; the default job
#   (out/default, as tools/demo.sh writes it), then the checks that run the program, the Python
#   module and the sources (Python tests, the Slurm cluster, the recipe schema, the generated docs,
#   the format check, the Cycles comparison);
# - build-asan/ (clang, AddressSanitizer and UndefinedBehaviorSanitizer, tools/sanitize.sh): the
#   GoogleTest programs, built and run once, there.
# Tests that need the shared third-party data (../shared/data, or $CADSYNTH_TEST_DATA) skip, saying
# so, without it; the Slurm test needs root (it starts slurmd) and skips, saying so, without it.
# docs/testing.md says why the GoogleTest programs run only under the sanitizers.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Each step's wall time is printed as it ends ("ci: build took 455 s"), so a slow CI log says where
# its time went (docs/testing.md keeps the budget).
step() {
  local name="$1" start=$SECONDS
  shift
  "$@"
  echo "ci: $name took $((SECONDS - start)) s"
}
release_checks() { (cd "$root/build" && ctest --output-on-failure --parallel "$(nproc)" --timeout 900); }
step setup "$root/tools/setup.sh" --tests
step build "$root/tools/build.sh" -DCADSYNTH_BUILD_TESTS=OFF
step default_job "$root/build/tools/cadsynth" generate -o "$root/out/default" --overwrite
step report "$root/build/tools/cadsynth" report "$root/out/default" --verify
"$root/tools/seed_test_costs.sh" "$root/build"
step release_checks release_checks
step sanitized_build_and_suite "$root/tools/sanitize.sh"
echo "ci: all steps took $SECONDS s"
