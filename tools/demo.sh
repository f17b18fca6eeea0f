#!/usr/bin/env bash
# Installs what is missing, builds, and runs the default job: a BOP dataset of the built-in parts
# in ./out/default (no input files needed), verified, with its report in out/default/report.html.
# Extra arguments go to `cadsynth generate`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
"$root/tools/build.sh"
"$root/build/tools/cadsynth" generate -o "$root/out/default" --overwrite "$@"
"$root/build/tools/cadsynth" report "$root/out/default" --verify
echo "open $root/out/default/report.html in a browser to see what the dataset holds"
