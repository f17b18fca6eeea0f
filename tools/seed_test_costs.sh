#!/usr/bin/env bash
# Gives a build tree with no test history (a fresh clone's) the tests' measured costs, so that
# ctest starts the longest tests first instead of leaving a 50-second test to run alone at the end
# of the suite. The costs are tests/ctest_costs.txt (seconds per test on the 2-core sandbox: the
# GoogleTest programs in the sanitizer build, where tools/test.sh runs them, the checks of the
# program and the Python module in Release; ctest's own CTestCostData.txt format). A tree that
# already has costs keeps them; ctest updates them after every run. Stale or missing entries only change the order, never a result.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:?usage: seed_test_costs.sh BUILD_DIR}"
costs="$build/Testing/Temporary/CTestCostData.txt"
[ -f "$costs" ] && exit 0
mkdir -p "$(dirname "$costs")"
cp "$root/tests/ctest_costs.txt" "$costs"
