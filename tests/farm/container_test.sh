#!/usr/bin/env bash
# The container image built from scratch and checked (tools/container.sh): where buildah and
# debootstrap are installed and the test runs as root; skipped (exit 77) elsewhere, saying why.
set -uo pipefail
root=${1:?usage: container_test.sh SOURCE_DIR}
if [ "$(id -u)" -ne 0 ]; then
  echo "skipped: tools/container.sh needs root (debootstrap, buildah's chroot isolation)"
  exit 77
fi
for tool in buildah debootstrap; do
  if ! command -v "$tool" > /dev/null; then
    echo "skipped: $tool is not installed (apt-get install buildah debootstrap to run this test)"
    exit 77
  fi
done
exec "$root/tools/container.sh"
