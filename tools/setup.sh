#!/usr/bin/env bash
# Installs the Debian 12 packages cadsynth builds with, if any are missing. Run as root (or with
# sudo available). Does nothing, and needs no network, when everything is already there.
#   tools/setup.sh            what building and running cadsynth needs
#   tools/setup.sh --tests    also Slurm and munge (a test starts a single-node Slurm cluster),
#                             clang-format (a test checks the formatting), clang and its
#                             sanitizer runtimes (the sanitizer build, tools/sanitize.sh),
#                             pytest (the Python module's tests), python3-jsonschema and
#                             python3-yaml (the recipe's JSON Schema checked by an independent
#                             validator)
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev
  libocct-foundation-dev libocct-ocaf-dev libocct-visualization-dev
  libcgal-dev libeigen3-dev libassimp-dev libembree-dev libopencv-dev libtbb-dev
  libyaml-cpp-dev libgtest-dev libbenchmark-dev nlohmann-json3-dev libmatio-dev zlib1g-dev
  libcli11-dev libxxhash-dev libbullet-dev libbullet-extras-dev libfcl-dev
  libhdf5-dev
  pybind11-dev python3-dev python3-numpy python3-torch
)
case "${1:-}" in
  --tests) packages+=(slurm-wlm munge clang-format clang libclang-rt-14-dev python3-pytest
                     python3-jsonschema python3-yaml) ;;
  "") ;;
  *) echo "usage: $0 [--tests]" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: run as root to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
