#!/usr/bin/env bash
# Webdataset archives on a farm (issue 46): writing, reading for training, merging.
#   tools/bench/archive_bench.sh [PARALLEL]
# 1. The default job (432 frames) as one process, with and without `formats: webdataset`.
# 2. The same job as 100 archive shards (`--shard i/100`, PARALLEL at a time, default 2): the
#    whole array's wall time, then `cadsynth merge` of the archive tree.
# 3. The archives read back through cadsynth.torch.ArchiveDataset by a DataLoader with 0 and 2
#    workers (batches of 8, masks decoded), frames per second; and, for scale, the same frames
#    rendered by cadsynth.torch.FrameDataset.
# 4. 1,000 small shards (3 scenes x 360 views at 64 x 48) with and without archives: the array's
#    wall time and `cadsynth merge`, seconds.
set -euo pipefail
# Keep the build still while this runs: shards of another executable are refused (run key).
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
parallel=${1:-2}
cd "$root"
exe=$root/build/tools/cadsynth
work=$(mktemp -d /tmp/cadsynth_archive.XXXXXX)
trap 'rm -rf "$work"' EXIT
export CADSYNTH_CACHE=$work/cache
printf 'output: {formats: [bop, webdataset]}\n' > "$work/default_wds.yaml"
printf 'output: {formats: [bop]}\n' > "$work/default.yaml"
seconds() {  # COMMAND...: its wall time in seconds; exits naming it when it fails
  local s
  s=$(date +%s.%N)
  "$@" > "$work/last.log" 2>&1 || { echo "FAILED: $* ($(tail -3 "$work/last.log"))" >&2; exit 1; }
  echo "$(date +%s.%N) - $s" | bc
}
"$exe" generate "$work/default.yaml" -o "$work/warm" --quiet > /dev/null  # fills the part cache
echo "default job, one process, bop only: $(seconds "$exe" generate "$work/default.yaml" -o "$work/one" --quiet) s"
echo "default job, one process, bop + webdataset: $(seconds "$exe" generate "$work/default_wds.yaml" -o "$work/one_wds" --quiet) s"
shards() {  # RECIPE COUNT DIR
  seq 0 $(($2 - 1)) | xargs -P "$parallel" -I{} "$exe" generate "$1" -o "$3" --shard "{}/$2" --quiet
}
echo "default job, 100 archive shards ($parallel at a time): $(seconds shards "$work/default_wds.yaml" 100 "$work/farm") s"
echo "  archives: $(ls "$work"/farm/webdataset/*.tar | wc -l), $(du -sb "$work/farm/webdataset" | cut -f1) bytes"
cp -a "$work/farm" "$work/farm_copy"
PYTHONPATH=$root/build/python /usr/bin/python3 - "$work/farm" "$work/default.yaml" <<'PY'
import sys, time
from torch.utils.data import DataLoader
from cadsynth.torch import ArchiveDataset, FrameDataset, collate
for workers in (0, 2):
    t = time.perf_counter(); n = 0
    for batch in DataLoader(ArchiveDataset(sys.argv[1]), batch_size=8, num_workers=workers,
                            collate_fn=collate):
        n += len(batch["im_id"])
    dt = time.perf_counter() - t
    print(f"ArchiveDataset, {workers} workers: {n} frames in {dt:.2f} s, {n / dt:.0f} frames/s")
t = time.perf_counter(); n = 0
for batch in DataLoader(FrameDataset(sys.argv[2]), batch_size=8, num_workers=0, collate_fn=collate):
    n += len(batch["im_id"])
dt = time.perf_counter() - t
print(f"FrameDataset (rendering), 0 workers: {n} frames in {dt:.2f} s, {n / dt:.0f} frames/s")
PY
echo "merge of the 100 archive shards: $(seconds "$exe" merge "$work/farm_copy") s"
small="camera: {width: 64, height: 48, fx: 52.5, fy: 52.5, cx: 31.5, cy: 23.5}
sweep: {yaw: {from: 0, to: 355, step: 5}, pitch: [20, 35, 50, 65, 80], radius: [0.7 m]}"
printf '%s\noutput: {formats: [bop]}\n' "$small" > "$work/small.yaml"
printf '%s\noutput: {formats: [bop, webdataset]}\n' "$small" > "$work/small_wds.yaml"
echo "1,000 small shards, bop: $(seconds shards "$work/small.yaml" 1000 "$work/s1") s"
echo "  merge: $(seconds "$exe" merge "$work/s1") s"
echo "1,000 small shards, bop + webdataset: $(seconds shards "$work/small_wds.yaml" 1000 "$work/s2") s"
echo "  merge (restoring from 1,000 manifests): $(seconds "$exe" merge "$work/s2") s"
