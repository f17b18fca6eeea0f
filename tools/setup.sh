#!/usr/bin/env bash
# Installs the Debian 12 packages cadsynth builds with, if any are missing. Run as root (or with
# sudo available). Does nothing, and needs no network, when everything is already there.
#   tools/setup.sh            what building and running cadsynth needs (python3-matplotlib
#                             draws `cadsynth report`'s plots)
#   tools/setup.sh --tests    also Slurm and munge (a test starts a single-node Slurm cluster),
#                             clang-format (a test checks the formatting), clang and its
#                             sanitizer runtimes (the sanitizer build, tools/sanitize.sh),
#                             pytest (the Python module's tests), python3-jsonschema and
#                             python3-yaml (the recipe's JSON Schema checked by an independent
#                             validator), Node.js, and the kubernetes-models npm package (pinned
#                             by tools/kubernetes/package-lock.json, fetched from npm's registry
#                             by tools/kubernetes/fetch_packages.py into tools/kubernetes/
#                             node_modules): the Kubernetes API schema the manifests are checked
#                             against, blender (3.4: the physically based mode checked
#                             against Cycles, tools/cycles/; the test skips without it) and
#                             chromium (headless: `cadsynth report`'s page opened in a browser)
#   tools/setup.sh --image    the container image's build stage (Dockerfile): what building
#                             needs, without PyTorch (the image leaves it out: 1.5 GB for the
#                             optional cadsynth.torch)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

packages=(
  cmake ninja-build g++ pkg-config
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev
  libocct-foundation-dev libocct-ocaf-dev libocct-visualization-dev
  libcgal-dev libeigen3-dev libassimp-dev libembree-dev libopencv-dev libtbb-dev
  libyaml-cpp-dev libgtest-dev libbenchmark-dev nlohmann-json3-dev libmatio-dev zlib1g-dev
  libcli11-dev libxxhash-dev libbullet-dev libbullet-extras-dev libfcl-dev
  libhdf5-dev libssl-dev libfontconfig-dev libpng-dev libjpeg62-turbo-dev libopenexr-dev
  pybind11-dev python3-dev python3-numpy python3-torch python3-matplotlib
)
case "${1:-}" in
  --tests) packages+=(slurm-wlm munge clang-format clang libclang-rt-14-dev python3-pytest
                     python3-jsonschema python3-yaml blender chromium)
           # Debian's nodejs, unless a Node.js is already installed (another vendor's). Not
           # Debian's npm, which brings about 400 packages: fetch_packages.py does its work here.
           command -v node > /dev/null || packages+=(nodejs) ;;
  --image) packages=("${packages[@]/python3-torch}")
           packages=("${packages[@]/python3-matplotlib}") ;;
  "") ;;
  *) echo "usage: $0 [--tests | --image]" >&2; exit 2 ;;
esac

# The Kubernetes API schema for the manifests' check (tests/farm/kubernetes_test.py), from npm's
# registry, checked against the lock file's hashes; once (again when the lock file changes).
# Without the registry the check is skipped, saying why; nothing else needs it.
install_kubernetes_schema() {
  [ "${1:-}" = "--tests" ] || return 0
  local folder=$root/tools/kubernetes
  if [ -f "$folder/node_modules/.package-lock.json" ] &&
     [ "$folder/node_modules/.package-lock.json" -nt "$folder/package-lock.json" ]; then
    return 0
  fi
  echo "setup: fetching tools/kubernetes' npm packages (kubernetes-models, the Kubernetes API schema)"
  python3 "$folder/fetch_packages.py" ||
    echo "setup: warning: fetching them failed; the Kubernetes manifests' schema check will be skipped" >&2
}

missing=()
for p in "${packages[@]}"; do
  [ -n "$p" ] || continue
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  install_kubernetes_schema "${1:-}"
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
install_kubernetes_schema "${1:-}"
