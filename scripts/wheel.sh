#!/bin/bash
# wheel.sh: the platform wheel of the Python package, with the static
# wsgemu and wsgctl inside it (wsgemu/bin/), so that `pip install
# wsgemu-*.whl` gives the client, the pytest fixture and the emulator in one
# step. The programs are linked statically (cmake -DWSG_STATIC=ON, as for
# the container image), so they need no libc of the installing machine: the
# wheel is tagged py3-none-<platform> (e.g. linux_x86_64), not manylinux.
# Built offline with Debian's setuptools and wheel (pip --no-build-isolation
# --no-index) from a copy of python/, so the source tree stays clean.
#
# Usage: scripts/wheel.sh [--build-dir DIR] [--out DIR]
#   --build-dir DIR  the static build tree (default build-static)
#   --out DIR        where the wheel goes (default DIR of --build-dir/wheel)
# Prints the wheel's path on stdout, and what it does as it goes (the
# build's progress among it) on stderr. Run scripts/deps.sh --test first.
set -eu

ME=wheel.sh
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$SRC/build-static
OUT=
PY=/usr/bin/python3   # Debian's: its setuptools and wheel build the package

usage() { echo "usage: $ME [--build-dir DIR] [--out DIR]" >&2; exit 2; }
while [ $# -gt 0 ]; do
    case $1 in
    --build-dir) [ $# -ge 2 ] || usage; BUILD=$2; shift 2 ;;
    --out) [ $# -ge 2 ] || usage; OUT=$2; shift 2 ;;
    *) usage ;;
    esac
done
[ -n "$OUT" ] || OUT=$BUILD/wheel

# Only the two programs: tests are not built. stdout is the wheel's path
# alone: the rest goes to stderr.
echo "$ME: static build of wsgemu and wsgctl in $BUILD" >&2
cmake -S "$SRC" -B "$BUILD" -DWSG_STATIC=ON -DWSG_SANITIZE=OFF \
    -DBUILD_TESTING=OFF >/dev/null
cmake --build "$BUILD" --parallel "$(nproc 2>/dev/null || echo 2)" \
    --target wsgemu wsgctl >&2

stage=$BUILD/wheel-src
rm -rf "$stage" && mkdir -p "$stage/wsgemu/bin"
cp "$SRC/python/pyproject.toml" "$SRC/python/README.md" "$stage/"
cp "$SRC/python/wsgemu/"*.py "$SRC/python/wsgemu/py.typed" "$stage/wsgemu/"
for p in "$BUILD/wsgemu" "$BUILD/tools/wsgctl"; do
    # A dynamic program would fail on a machine with another libc: refuse.
    if readelf -lW "$p" | grep -q INTERP || readelf -d "$p" | grep -q NEEDED; then
        echo "$ME: $p is dynamically linked; the wheel needs a static one" >&2
        exit 1
    fi
    install -m 755 "$p" "$stage/wsgemu/bin/"
    strip "$stage/wsgemu/bin/$(basename "$p")"
done

# The platform as wheel tags spell it: linux-x86_64 -> linux_x86_64.
plat=$("$PY" -c 'import sysconfig; print(sysconfig.get_platform().replace("-", "_").replace(".", "_"))')
mkdir -p "$OUT"
rm -f "$OUT"/wsgemu-*-"$plat".whl
echo "$ME: pip wheel (Debian's setuptools, no index) into $OUT" >&2
PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 \
    "$PY" -m pip wheel --quiet --no-deps --no-index --no-build-isolation \
    --config-settings=--build-option=--plat-name="$plat" -w "$OUT" "$stage"
ls "$OUT"/wsgemu-*-py3-none-"$plat".whl
