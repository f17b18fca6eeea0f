#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite with ctest; then builds it again
# with AddressSanitizer and UndefinedBehaviorSanitizer (build-asan/, tools/sanitize.sh) and runs
# it there. Tests that need the shared third-party data (../shared/data, or $CADSYNTH_TEST_DATA)
# skip, saying so, without it; the Slurm test needs root (it starts slurmd) and skips, saying so,
# without it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh" --tests
"$root/tools/build.sh"
"$root/tools/seed_test_costs.sh" "$root/build"
cd "$root/build"
ctest --output-on-failure --parallel "$(nproc)" --timeout 900
"$root/tools/sanitize.sh"
