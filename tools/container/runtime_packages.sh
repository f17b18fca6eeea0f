#!/usr/bin/env bash
# The Debian packages whose shared libraries the installed cadsynth loads (the executable and the
# Python module under PREFIX), one per line: what the container's runtime stage installs instead
# of the build stage's compilers and headers.
#   tools/container/runtime_packages.sh PREFIX
set -euo pipefail
prefix=${1:?usage: runtime_packages.sh PREFIX}
objects=("$prefix/bin/cadsynth")
while IFS= read -r -d '' f; do objects+=("$f"); done < <(find "$prefix/lib" -name '_cadsynth*.so' -print0)
ldd "${objects[@]}" | awk '/=> \// { print $3 }' | sort -u | while read -r lib; do
  # dpkg knows the path it installed (/usr/lib/...; /lib is a link to it on Debian 12).
  dpkg -S "$lib" 2>/dev/null || dpkg -S "$(readlink -f "$lib")" 2>/dev/null ||
    dpkg -S "${lib/#\/lib\//\/usr\/lib\/}" 2>/dev/null || { echo "no package has $lib" >&2; exit 1; }
done | cut -d: -f1 | sort -u
