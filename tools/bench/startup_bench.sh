#!/usr/bin/env bash
# Warm start-up and whole-process time of a farm shard (issue 46, item 6), interleaved against
# another build and the Embree + OpenCV floor:
#   [CADSYNTH_BUILD_DIR=build] tools/bench/startup_bench.sh OTHER_CADSYNTH [ROUNDS]
# Each round runs, one after the other: tools/bench/seed_1.yaml (the reference paper's four
# speed-reducer STLs, one view) with this tree's build (warm part cache, then no cache), with
# OTHER_CADSYNTH (its own warm cache), `cadsynth --version` (the process start alone),
# tools/bench/seed_288.yaml (the same meshes over 288 views) with both builds, and the floor:
# the build's bench/cadsynth_bench_render BM_EndToEnd with 2 threads on the same views. The floor
# writes its files to /dev/shm, so the 288-view runs write there too (seed_288_warm,
# seed_288_other_warm); seed_288_disk is this build's run into a folder beside the caches, as
# `--overwrite` over the last run's 2,900 files (on ext4 the unlinking and the new inodes cost
# seconds: docs/benchmarks.md), and seed_288_floor_disk the floor writing beside it. Prints each
# measure's times in seconds, sorted. Needs ../shared/data (the meshes).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
other=$(realpath "${1:?usage: startup_bench.sh OTHER_CADSYNTH [ROUNDS]}")
rounds=${2:-8}
cd "$root"
build=${CADSYNTH_BUILD_DIR:-build}
work=$(mktemp -d /tmp/cadsynth_startup.XXXXXX)
shm=$(mktemp -d /dev/shm/cadsynth_startup.XXXXXX)
trap 'rm -rf "$work" "$shm"' EXIT
new=$build/tools/cadsynth
timed() {  # NAME COMMAND...: prints "NAME seconds"
  local name=$1
  shift
  /usr/bin/time -f "$name %e" "$@" 2>&1 > /dev/null | grep "^$name "
}
# Fill both caches first.
CADSYNTH_CACHE=$work/cache_new "$new" generate tools/bench/seed_288.yaml -o "$work/o" --overwrite --quiet > /dev/null 2>&1
CADSYNTH_CACHE=$work/cache_other "$other" generate tools/bench/seed_288.yaml -o "$work/o" --overwrite --quiet > /dev/null 2>&1
for _ in $(seq "$rounds"); do
  CADSYNTH_CACHE=$work/cache_new timed seed_1_warm "$new" generate tools/bench/seed_1.yaml -o "$work/a" --overwrite --quiet
  CADSYNTH_CACHE=$work/cache_other timed seed_1_other_warm "$other" generate tools/bench/seed_1.yaml -o "$work/b" --overwrite --quiet
  timed seed_1_no_cache "$new" generate tools/bench/seed_1.yaml -o "$work/c" --overwrite --quiet --no-cache
  timed version "$new" --version
  CADSYNTH_CACHE=$work/cache_new timed seed_288_warm "$new" generate tools/bench/seed_288.yaml -o "$shm/d" --overwrite --quiet
  CADSYNTH_CACHE=$work/cache_other timed seed_288_other_warm "$other" generate tools/bench/seed_288.yaml -o "$shm/e" --overwrite --quiet
  CADSYNTH_CACHE=$work/cache_new timed seed_288_disk "$new" generate tools/bench/seed_288.yaml -o "$work/d" --overwrite --quiet
  CADSYNTH_BENCH_RECIPE=tools/bench/seed_288.yaml "$build/bench/cadsynth_bench_render" \
    --benchmark_filter='BM_EndToEnd/2' --benchmark_min_time=0.1 2>&1 |
    awk '/BM_EndToEnd/ {printf "seed_288_floor %.2f\n", $2 / 1000}'
  CADSYNTH_BENCH_OUT=$work/floor CADSYNTH_BENCH_RECIPE=tools/bench/seed_288.yaml \
    "$build/bench/cadsynth_bench_render" --benchmark_filter='BM_EndToEnd/2' \
    --benchmark_min_time=0.1 2>&1 |
    awk '/BM_EndToEnd/ {printf "seed_288_floor_disk %.2f\n", $2 / 1000}'
done | sort -k1,1 -k2n | awk '{t[$1] = t[$1] " " $2} END {for (k in t) print k ":" t[k]}' | sort
