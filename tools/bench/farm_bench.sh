#!/bin/bash
# Farm benchmark: the same recipe as one process with all threads, as 2 shards side by side with
# one thread each, and as 100 shards (2 at a time) followed by merge; checks every result is
# byte-identical to the single run and prints the wall times.
#   tools/bench/farm_bench.sh [RECIPE.yaml] [WORKDIR]   (default: recipes/paper_sweep.yaml, /tmp)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
exe=$root/build/tools/cadsynth
recipe=$(realpath "${1:-$root/recipes/paper_sweep.yaml}")
work=$(mktemp -d "${2:-/tmp}/cadsynth_farm_bench.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work"
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

t0=$(now)
"$exe" generate "$recipe" -o single --quiet
t1=$(now)
echo "one process, $(nproc) threads: $(elapsed "$t0" "$t1") s"

t0=$(now)
"$exe" generate "$recipe" --shard 0/2 --threads 1 -o two --quiet &
"$exe" generate "$recipe" --shard 1/2 --threads 1 -o two --quiet &
wait
t1=$(now)
"$exe" merge two > /dev/null
t2=$(now)
echo "2 shards in parallel, 1 thread each: $(elapsed "$t0" "$t1") s, merge $(elapsed "$t1" "$t2") s"
diff -rq -x run.json single two > /dev/null && echo "  identical to the single run"
rm -rf two

t0=$(now)
seq 0 99 | xargs -P 2 -I{} "$exe" generate "$recipe" --shard {}/100 --threads 1 -o hundred --quiet
t1=$(now)
/usr/bin/time -f "  merge peak memory %M KB" "$exe" merge hundred
t2=$(now)
echo "100 shards, 2 at a time: $(elapsed "$t0" "$t1") s; merge of 100 shards: $(elapsed "$t1" "$t2") s"
diff -rq -x run.json single hundred > /dev/null && echo "  identical to the single run"
