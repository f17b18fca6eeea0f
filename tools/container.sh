#!/usr/bin/env bash
# Builds cadsynth's container image with Debian's own tools (no image registry, no daemon) and
# checks it. Run as root on Debian 12 (tools/container.sh installs buildah and debootstrap if
# missing):
#   tools/container.sh          build the base and the image, then check the image
#   tools/container.sh check    check an image built before
# 1. Base: `debootstrap --variant=minbase bookworm` from this machine's Debian mirror, with the
#    bookworm-updates and security suites it uses, without documentation, manuals or
#    translations (tools/container/dpkg-slim.cfg), committed as localhost/cadsynth-base:bookworm
#    (made once; remove the image to make it again).
# 2. Image: `buildah bud --isolation chroot` of the Dockerfile on that base, tagged
#    localhost/cadsynth:latest (podman's runtime cannot set its resource limits on the project's
#    machines; chroot isolation needs none).
# 3. Check, each a failure when it does not hold: the image runs as user cadsynth, has no
#    compiler and no Mesa, and writes only under /out; a STEP file it writes reads back as
#    outside it; the default job written in it equals, byte for byte,
#    the one this tree's build/tools/cadsynth writes (when built); the Python module renders a
#    frame in it. Prints the build's minutes and the image's size.
# The test container_image (tests/CMakeLists.txt) runs this where buildah and debootstrap are
# installed and skips elsewhere.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mode=${1:-all}
base=localhost/cadsynth-base:bookworm
image=localhost/cadsynth:latest
work=${CADSYNTH_CONTAINER_WORK:-/var/tmp/cadsynth-container}
say() { echo "container: $*"; }
fail() { echo "container: FAILED: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || fail "run as root (buildah's chroot isolation and debootstrap need it)"
if ! command -v buildah > /dev/null || ! command -v debootstrap > /dev/null; then
  say "installing buildah and debootstrap"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends buildah debootstrap
fi
mkdir -p "$work"

# This machine's Debian mirror (deb822 or one-line sources), else Debian's CDN.
mirror() {
  local uri
  uri=$(grep -hoE '^URIs: *[^ ]+/debian/?$' /etc/apt/sources.list.d/*.sources 2>/dev/null | head -1 |
        sed 's/^URIs: *//')
  [ -n "$uri" ] || uri=$(grep -hoE '^deb +[^ ]+/debian/? +bookworm ' /etc/apt/sources.list 2>/dev/null |
                         head -1 | awk '{print $2}')
  echo "${uri:-http://deb.debian.org/debian}"
}

make_base() {
  if buildah inspect --type image "$base" > /dev/null 2>&1; then
    say "base $base present"
    return
  fi
  local url rootfs ctr
  url=$(mirror)
  rootfs=$work/rootfs
  rm -rf "$rootfs"
  say "debootstrap bookworm (minbase) from $url"
  debootstrap --variant=minbase bookworm "$rootfs" "$url" > "$work/debootstrap.log" 2>&1 ||
    { tail -20 "$work/debootstrap.log" >&2; fail "debootstrap (log: $work/debootstrap.log)"; }
  local security=${url%/debian*}/debian-security
  cat > "$rootfs/etc/apt/sources.list" <<SOURCES
deb $url bookworm main
deb $url bookworm-updates main
deb $security bookworm-security main
SOURCES
  rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
  # The base keeps no documentation, manuals or translations either, and its dpkg leaves them out
  # of what the image installs later (tools/container/dpkg-slim.cfg; the licences stay).
  cp "$root/tools/container/dpkg-slim.cfg" "$rootfs/etc/dpkg/dpkg.cfg.d/cadsynth-slim"
  find "$rootfs/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete
  find "$rootfs/usr/share/locale" -mindepth 1 -maxdepth 1 -not -name locale.alias -exec rm -rf {} +
  rm -rf "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/*
  ctr=$(buildah from scratch)
  tar -C "$rootfs" -cf "$work/rootfs.tar" .
  buildah add "$ctr" "$work/rootfs.tar" / > /dev/null
  buildah config --cmd /bin/bash --env LANG=C.UTF-8 "$ctr"
  buildah commit --rm "$ctr" "$base" > /dev/null
  rm -rf "$rootfs" "$work/rootfs.tar"
  say "base $base committed"
}

build_image() {
  say "buildah bud --isolation chroot (log: $work/build.log)"
  # The build context without build trees, git objects or fetched npm packages (.dockerignore).
  buildah bud --isolation chroot --layers=false --build-arg BASE="$base" -t "$image" \
    -f "$root/Dockerfile" "$root" > "$work/build.log" 2>&1 ||
    { tail -30 "$work/build.log" >&2; fail "buildah bud (log: $work/build.log)"; }
}

check_image() {
  local ctr mnt out marker
  ctr=$(buildah from "$image")
  trap 'buildah rm "$ctr" > /dev/null 2>&1 || true' RETURN
  mnt=$(buildah mount "$ctr")
  out=$work/out
  rm -rf "$out"
  mkdir -p "$out"
  chown 1000:1000 "$out"
  run() { buildah run --isolation chroot -v "$out:/out" "$ctr" -- "$@"; }

  [ "$(run id -un)" = cadsynth ] || fail "the image does not run as user cadsynth"
  if run sh -c 'command -v gcc cc c++ g++ clang ld cpp || true' | grep -q .; then
    fail "the image holds a compiler: $(run sh -c 'command -v gcc cc c++ g++ clang ld cpp || true')"
  fi
  marker=$work/marker
  touch "$marker"
  sleep 1
  run cadsynth generate -o /out/default --quiet
  # STEP written and read back through OpenCASCADE's XDE, whose resources the image keeps.
  run cadsynth variants --export-step /out/steps > /dev/null
  run cadsynth inspect /out/steps/planetary_gearbox_0_planetary_0.step | tail -n +2 > "$work/inspect.txt"
  run python3 -c '
import cadsynth, zlib
frame = next(iter(cadsynth.Recipe.default().prepare().frames(masks=False)))
print("python", cadsynth.__version__, frame["rgb"].shape, zlib.crc32(frame["rgb"].tobytes()))
' > "$work/python.txt"
  cat "$work/python.txt"
  # Nothing written outside /out (buildah itself provides /etc/hosts, resolv.conf, hostname).
  local stray
  stray=$(cd "$mnt" && find . -xdev -newer "$marker" \( -type f -o -type l \) \
            -not -path './etc/hosts' -not -path './etc/resolv.conf' -not -path './etc/hostname' \
            -not -path './run/*' -not -path './proc/*' -not -path './sys/*' -not -path './dev/*' |
          head -20)
  [ -z "$stray" ] || fail "the container wrote outside /out: $stray"
  [ -f "$out/default/camera.json" ] || fail "no dataset in /out/default"
  # No Mesa: its DRI drivers and LLVM (tools/container/no-mesa.control) are not in the image.
  local mesa
  mesa=$(find "$mnt/usr/lib" \( -name 'libLLVM*' -o -name '*_dri.so' -o -name 'libGLX_mesa*' \) | head -3)
  [ -z "$mesa" ] || fail "the image holds Mesa: $mesa"

  local host=$root/build/tools/cadsynth
  if [ -x "$host" ]; then
    rm -rf "$work/host"
    CADSYNTH_CACHE=$work/host_cache "$host" generate -o "$work/host/default" --quiet
    diff -r -x .cadsynth_cache -x run.json "$work/host/default" "$out/default" > "$work/diff.txt" ||
      fail "the dataset written in the container differs from $host's ($work/diff.txt)"
    local frames
    frames=$(find "$out/default" -path '*/rgb/*.png' | wc -l)
    say "the default job in the container equals this machine's build, byte for byte ($frames frames)"
    "$host" variants --export-step "$work/host/steps" > /dev/null
    "$host" inspect "$work/host/steps/planetary_gearbox_0_planetary_0.step" | tail -n +2 |
      diff - "$work/inspect.txt" > "$work/inspect_diff.txt" ||
      fail "cadsynth inspect of a STEP file differs in the container ($work/inspect_diff.txt)"
    say "a STEP file written and read in the container is read as outside it"
    local py
    py=$(PYTHONPATH=$root/build/python /usr/bin/python3 -c '
import cadsynth, zlib
frame = next(iter(cadsynth.Recipe.default().prepare().frames(masks=False)))
print("python", cadsynth.__version__, frame["rgb"].shape, zlib.crc32(frame["rgb"].tobytes()))
' 2>/dev/null || true)
    [ -z "$py" ] || [ "$py" = "$(cat "$work/python.txt")" ] ||
      fail "the Python module's first frame differs: '$py' here, '$(cat "$work/python.txt")' in the image"
  else
    say "no $host: the dataset was not compared with one written outside the container"
  fi
  buildah umount "$ctr" > /dev/null
  say "image $image: $(buildah images --format '{{.Size}}' "$image"), user cadsynth, no compiler, writes only /out"
}

start=$SECONDS
case "$mode" in
  all) make_base; build_image; say "built in $(( (SECONDS - start + 30) / 60 )) min ($((SECONDS - start)) s)"; check_image ;;
  check) check_image ;;
  *) echo "usage: $0 [check]" >&2; exit 2 ;;
esac
say "done in $((SECONDS - start)) s"
