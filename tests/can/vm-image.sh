#!/bin/bash
# vm-image.sh: prepare the virtual machine that tests/can/run.sh boots where
# the host's kernel has no SocketCAN. It holds Debian's amd64 kernel (made
# an uncompressed ELF vmlinux, which QEMU starts through its PVH entry: under
# emulation that saves the seconds the XZ decompressor would take on every
# boot), the kernel's SocketCAN modules (can, can-raw, can-dev, vcan) and
# sch_tbf (to make a slow bus) with a modules.dep, and a static busybox to
# be the VM's userland.
#
# Everything comes from the Debian archive through `apt-get download` and is
# unpacked with dpkg-deb into a cache; nothing is installed. The tools it
# needs (apt, dpkg, tar, xz) are installed by scripts/deps.sh --test.
#
# Usage: vm-image.sh [CACHE_DIR]
#   CACHE_DIR: $WSG_CAN_VM_CACHE, else ~/.cache/wsgemu/can-vm (where that
#   cannot be made, /tmp/wsgemu-can-vm-UID).
#   Prints the directory of the image: kernel, busybox, lib/modules/KVER/.
#   The first run downloads some 72 MB and keeps about 75 MB; later runs
#   find it ready (the kernel package is looked up each time, ~0.2 s, and
#   a newer one replaces the old image).
# Environment:
#   WSG_CAN_VM_KERNEL  the kernel package (default: what linux-image-amd64
#                      depends on, e.g. linux-image-6.1.0-56-amd64).
# Exit status: 0 ready; 77 cannot be had here (not amd64, tools missing;
# reason on stderr); 1 failed (a download among them).
# Safe to run concurrently: the cache is locked while it is prepared.
set -eu

ME=vm-image.sh
# Bumped whenever an image's contents change: older images are redone.
FORMAT=2
skip() { echo "$ME: $*" >&2; exit 77; }
# With QEMU here, an image that cannot be made is a failure, not a skip:
# the CAN tests must not quietly stop running where they could run.
fail() { echo "$ME: $*" >&2; exit 1; }
die() { echo "$ME: $*" >&2; exit 1; }

CACHE=${1:-${WSG_CAN_VM_CACHE:-}}
if [ -z "$CACHE" ]; then
    CACHE=${XDG_CACHE_HOME:-${HOME:-/nonexistent}/.cache}/wsgemu/can-vm
    # No home to write to (a CI user without one): a cache per user in /tmp.
    mkdir -p "$CACHE" 2>/dev/null || CACHE=${TMPDIR:-/tmp}/wsgemu-can-vm-$(id -u)
fi

[ "$(uname -m)" = x86_64 ] || skip "the VM runs amd64 test binaries: this host is $(uname -m)"
for tool in apt-get apt-cache dpkg-deb tar xz flock; do
    command -v "$tool" >/dev/null 2>&1 ||
        skip "$tool missing (scripts/deps.sh --test installs what the CAN VM needs)"
done
mkdir -p "$CACHE" 2>/dev/null || skip "cannot create the cache $CACHE"
exec 9>"$CACHE/.lock"
flock -w 600 9 || die "the cache $CACHE stayed locked for 10 minutes"

# As root, apt downloads as root (the _apt user may not write the cache)
# and may refresh stale package lists; otherwise it uses the lists it has.
APT_OPTS="-q -o Acquire::Retries=2 -o Acquire::http::Timeout=30"
APT_OPTS="$APT_OPTS -o Acquire::https::Timeout=30"
[ "$(id -u)" = 0 ] && APT_OPTS="$APT_OPTS -o APT::Sandbox::User=root"
updated=0
apt_update() {
    [ "$updated" = 0 ] && [ "$(id -u)" = 0 ] || return 1
    updated=1
    echo "$ME: apt-get update" >&2
    # shellcheck disable=SC2086
    timeout 300 apt-get $APT_OPTS update -qq >&2
}

# download PACKAGE: its .deb into $CACHE/dl; prints the path.
download() {
    local deb
    mkdir -p "$CACHE/dl"
    rm -f "$CACHE/dl/${1}_"*.deb
    # shellcheck disable=SC2086
    if ! (cd "$CACHE/dl" && timeout 300 apt-get $APT_OPTS download "$1" >&2); then
        # Lists older than the archive name versions it no longer has.
        apt_update || return 1
        # shellcheck disable=SC2086
        (cd "$CACHE/dl" && timeout 300 apt-get $APT_OPTS download "$1" >&2) ||
            return 1
    fi
    deb=$(ls "$CACHE/dl/${1}_"*.deb 2>/dev/null | head -n 1)
    [ -n "$deb" ] || return 1
    printf '%s\n' "$deb"
}

resolve_kernel() {
    apt-cache depends linux-image-amd64 2>/dev/null |
        awk '$1 == "Depends:" && $2 ~ /^linux-image-[0-9]/ { print $2; exit }'
}

# ---- busybox: one for every kernel ----
if [ ! -x "$CACHE/busybox" ]; then
    echo "$ME: fetching busybox-static" >&2
    deb=$(download busybox-static) || fail "cannot download busybox-static"
    rm -rf "$CACHE/busybox.x"
    mkdir -p "$CACHE/busybox.x"
    dpkg-deb -x "$deb" "$CACHE/busybox.x" || die "cannot unpack $deb"
    # Not installed: it would conflict with the dynamic busybox package.
    cp "$CACHE/busybox.x/bin/busybox" "$CACHE/busybox.new" ||
        die "no bin/busybox in $deb"
    chmod 755 "$CACHE/busybox.new"
    mv "$CACHE/busybox.new" "$CACHE/busybox"
    rm -rf "$CACHE/busybox.x" "$deb"
fi

# ---- the kernel ----
KPKG=${WSG_CAN_VM_KERNEL:-}
[ -n "$KPKG" ] || KPKG=$(resolve_kernel)
if [ -z "$KPKG" ] && apt_update; then
    KPKG=$(resolve_kernel)
fi
# Offline, or no lists: an image prepared earlier still serves (there is
# one at most: a new one replaces it).
ready_image() {
    local r
    for r in "$CACHE"/linux-image-*/.ready; do
        [ -f "$r" ] && [ "$(cat "$r")" = "$FORMAT" ] && { dirname "$r"; return; }
    done
}
if [ -z "$KPKG" ]; then
    img=$(ready_image)
    [ -n "$img" ] || fail "cannot find Debian's linux-image-amd64 (apt-get update?)"
    echo "$ME: linux-image-amd64 not found; using $img" >&2
    printf '%s\n' "$img"
    exit 0
fi
IMG="$CACHE/$KPKG"
if [ -f "$IMG/.ready" ] && [ "$(cat "$IMG/.ready")" = "$FORMAT" ]; then
    printf '%s\n' "$IMG"
    exit 0
fi

echo "$ME: preparing $KPKG (once: a 70 MB download)" >&2
if ! deb=$(download "$KPKG"); then
    img=$(ready_image)
    [ -n "$img" ] || fail "cannot download $KPKG"
    echo "$ME: cannot download $KPKG; using $img" >&2
    printf '%s\n' "$img"
    exit 0
fi
TMP="$IMG.tmp"
rm -rf "$TMP"
mkdir -p "$TMP/x"
# Only the kernel image and the SocketCAN modules: the whole package
# unpacks to some 400 MB. The paths hold for /lib/modules and for
# /usr/lib/modules.
dpkg-deb --fsys-tarfile "$deb" |
    tar -x -C "$TMP/x" --wildcards './boot/vmlinuz-*' \
        '*/kernel/net/can/*' '*/kernel/drivers/net/can/vcan.ko*' \
        '*/kernel/drivers/net/can/dev/*' '*/kernel/net/sched/sch_tbf.ko*' ||
    die "cannot unpack $deb"
vmz=$(ls "$TMP"/x/boot/vmlinuz-* 2>/dev/null | head -n 1)
[ -n "$vmz" ] || die "no kernel image in $deb"
KVER=${vmz##*/vmlinuz-}
moddir=$(find "$TMP/x" -type d -path "*/modules/$KVER" | head -n 1)
[ -n "$moddir" ] || die "no modules for $KVER in $deb"
find "$moddir" -name vcan.ko -o -name 'vcan.ko.*' | grep -q . ||
    die "$KPKG has no vcan module"
mkdir -p "$TMP/lib/modules"
mv "$moddir" "$TMP/lib/modules/$KVER"
# busybox's modprobe loads plain .ko files only.
find "$TMP/lib/modules" -name '*.ko.xz' -exec xz -d {} +
if find "$TMP/lib/modules" -name '*.ko.zst' | grep -q .; then
    command -v zstd >/dev/null 2>&1 || die "$KPKG has zstd modules: install zstd"
    find "$TMP/lib/modules" -name '*.ko.zst' -exec zstd -q -d --rm {} +
fi
"$CACHE/busybox" depmod -b "$TMP" "$KVER" || die "depmod failed"

# The bzImage carries the kernel as an XZ stream after its setup code: the
# first stream that decompresses to an ELF file is it. xz complains about
# the bytes after the stream, hence the unchecked status.
for off in $(LC_ALL=C grep -aboF "$(printf '\3757zXZ')" "$vmz" | cut -d: -f1); do
    tail -c +$((off + 1)) "$vmz" | xz -dc 2>/dev/null >"$TMP/kernel" || true
    [ "$(head -c 4 "$TMP/kernel" | od -An -tx1 | tr -d ' ')" = 7f454c46 ] && break
    rm -f "$TMP/kernel"
done
if [ ! -f "$TMP/kernel" ]; then
    echo "$ME: no ELF kernel inside $vmz: booting the bzImage (slower)" >&2
    cp "$vmz" "$TMP/kernel"
fi
cp "$CACHE/busybox" "$TMP/busybox"
echo "$KVER" >"$TMP/kver"
rm -rf "$TMP/x" "$deb"
echo "$FORMAT" >"$TMP/.ready"
# A newer kernel replaces the old images.
for old in "$CACHE"/linux-image-*; do
    [ "$old" = "$TMP" ] || rm -rf "$old"
done
mv "$TMP" "$IMG"
printf '%s\n' "$IMG"
