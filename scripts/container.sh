#!/bin/bash
# container.sh: build the wsgemu container image (Containerfile) with
# podman, from nothing but this tree and Debian's packages:
#   1. a static build of wsgemu and wsgctl (cmake -DWSG_STATIC=ON) in its
#      own build directory (default build-static), checked to have no
#      dynamic section: the image is FROM scratch, there is no libc in it;
#   2. a build context holding only those two programs (stripped);
#   3. podman build, tagged wsgemu:VERSION and wsgemu:latest.
# Then, if asked, saves the image to an archive or exports its root
# filesystem (for a machine whose runtime cannot run containers: run its
# entrypoint from there, see docs/container.md).
#
# Usage: scripts/container.sh [--build-dir DIR] [--tag NAME] [--save FILE]
#                             [--export DIR]
#   --build-dir DIR  the static build tree (default build-static)
#   --tag NAME       the image name (default localhost/wsgemu:VERSION, also
#                    tagged localhost/wsgemu:latest)
#   --save FILE      podman save the image to FILE (a docker-archive tar:
#                    `podman load -i FILE` or `docker load -i FILE`)
#   --export DIR     the image's root filesystem, unpacked into DIR
# Environment: PODMAN (default podman). podman's own settings apply, e.g.
#   CONTAINERS_STORAGE_CONF for another storage root (the test uses that).
# Run scripts/deps.sh --test first (podman, cmake, gcc, libc6-dev).
set -eu

ME=container.sh
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$SRC/build-static
TAG=
SAVE=
EXPORT=
PODMAN=${PODMAN:-podman}

usage() {
    echo "usage: $ME [--build-dir DIR] [--tag NAME] [--save FILE] [--export DIR]" >&2
    exit 2
}
while [ $# -gt 0 ]; do
    case $1 in
    --build-dir) [ $# -ge 2 ] || usage; BUILD=$2; shift 2 ;;
    --tag) [ $# -ge 2 ] || usage; TAG=$2; shift 2 ;;
    --save) [ $# -ge 2 ] || usage; SAVE=$2; shift 2 ;;
    --export) [ $# -ge 2 ] || usage; EXPORT=$2; shift 2 ;;
    *) usage ;;
    esac
done
command -v "$PODMAN" >/dev/null 2>&1 ||
    { echo "$ME: $PODMAN not found (scripts/deps.sh --test installs podman)" >&2; exit 1; }

# Temporary files (the context, a created container) go when we do.
ctx="" ctr=""
cleanup() {
    [ -z "$ctr" ] || "$PODMAN" rm -f "$ctr" >/dev/null 2>&1 || true
    [ -z "$ctx" ] || rm -rf "$ctx"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "$ME: static build of wsgemu and wsgctl in $BUILD"
# Tests are not built: only the two programs go into the image. The
# build's progress shows.
cmake -S "$SRC" -B "$BUILD" -DWSG_STATIC=ON -DWSG_SANITIZE=OFF \
    -DBUILD_TESTING=OFF >/dev/null
cmake --build "$BUILD" --parallel "$(nproc 2>/dev/null || echo 2)" \
    --target wsgemu wsgctl
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$BUILD/CMakeCache.txt")
[ -n "$version" ] || { echo "$ME: no project version in $BUILD" >&2; exit 1; }
[ -n "$TAG" ] || TAG=localhost/wsgemu:$version

ctx=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-ctx.XXXXXX")
for p in "$BUILD/wsgemu" "$BUILD/tools/wsgctl"; do
    # A dynamic program would start in the image only to fail to find its
    # loader: refuse it here, with the reason.
    if readelf -lW "$p" | grep -q INTERP || readelf -d "$p" | grep -q NEEDED; then
        echo "$ME: $p is dynamically linked; FROM scratch needs a static one" >&2
        exit 1
    fi
    cp "$p" "$ctx/"
    strip "$ctx/$(basename "$p")"
done

echo "$ME: podman build $TAG (wsgemu $version), from the two programs alone"
tags=(--tag "$TAG")
case $TAG in
*:"$version") tags+=(--tag "${TAG%:*}:latest") ;;
esac
"$PODMAN" build --quiet --layers=false --file "$SRC/Containerfile" \
    --build-arg "WSG_VERSION=$version" "${tags[@]}" "$ctx" >/dev/null
echo "$ME: built $TAG"

if [ -n "$SAVE" ]; then
    echo "$ME: podman save $TAG to $SAVE"
    "$PODMAN" save --quiet --format docker-archive --output "$SAVE" "$TAG"
    echo "$ME: saved $TAG to $SAVE"
fi
if [ -n "$EXPORT" ]; then
    # A created (never started) container: creating it runs nothing, so
    # this works where the runtime refuses to start containers.
    echo "$ME: podman export $TAG to $EXPORT"
    ctr=$("$PODMAN" create "$TAG")
    mkdir -p "$EXPORT"
    "$PODMAN" export "$ctr" | tar -x -C "$EXPORT"
    "$PODMAN" rm "$ctr" >/dev/null
    ctr=""
    echo "$ME: exported the root filesystem of $TAG to $EXPORT"
fi
