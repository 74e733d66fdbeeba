#!/bin/sh
# Installs the Debian packages wsgemu needs, and only those that are
# missing, so it is quick and offline-safe on a prepared machine. Runs
# apt-get as root, or through sudo when not root. Says what it installs
# and how much it downloads before it starts, and apt-get shows each
# download and each package it sets up as it goes.
#
# Usage: scripts/deps.sh          what building and running needs (the
#                                 README's quick start)
#        scripts/deps.sh --test   that and what the whole test suite needs
#                                 (scripts/test.sh, the README's test
#                                 command): valgrind, clang, QEMU, podman,
#                                 Python, Chromium, ...
#        --print (after either)   print the packages, one a line, and
#                                 install nothing (tests/deps_list.sh)
set -eu

test_deps=0
print=0
for a in "$@"; do
    case $a in
    --test) test_deps=1 ;;
    --print) print=1 ;;
    *)
        echo "usage: scripts/deps.sh [--test] [--print]" >&2
        exit 2
        ;;
    esac
done

# ---- building and running ----
pkgs="cmake make gcc libc6-dev"
# Scripts on the gripper run on Debian's Lua 5.2, found with pkg-config.
pkgs="$pkgs pkgconf liblua5.2-dev"
# The web page (--web) is served by GNU libmicrohttpd, found with
# pkg-config; its -dev package brings GnuTLS's headers, which the static
# stand-in for GnuTLS is checked against (src/daemon/web/gnutls_none.c).
pkgs="$pkgs libmicrohttpd-dev"
# The MuJoCo plant (--physics mujoco) links Debian's MuJoCo 2.2, found
# through its CMake config (without it the build leaves the plant out).
pkgs="$pkgs libmujoco-dev"
# setcap, for an ordinary user who wants the real gripper's port 1000
# (README: Port 1000): `sudo setcap cap_net_bind_service=+ep build/wsgemu`.
pkgs="$pkgs libcap2-bin"

# ---- the test suite ----
if [ "$test_deps" = 1 ]; then
    # The memcheck test (tests/memcheck.sh) runs the daemon under valgrind.
    pkgs="$pkgs valgrind"
    # The .deb and its test (tests/package/run.sh): CPack's Depends come from
    # dpkg-shlibdeps (dpkg-dev), which CPack feeds the programs it finds with
    # file; man renders the man pages and systemd-analyze verifies the unit.
    pkgs="$pkgs dpkg-dev file man-db systemd"
    # The package test also holds the .deb to Debian's own checks: lintian,
    # errors and warnings (tests/package/run.sh).
    pkgs="$pkgs lintian"
    # ... and runs the logrotate snippet it installs.
    pkgs="$pkgs logrotate"
    # The container image (scripts/container.sh, tests/container/run.sh):
    # podman builds and runs it; runc because crun refuses a cgroup v1/v2
    # hybrid; ip brings up loopback where the test runs the exported rootfs.
    pkgs="$pkgs podman runc iproute2"
    # The Kubernetes manifests' tests (tests/kube): podman kube play builds
    # its pods' infra image around catatonit; python3-yaml reads the
    # manifests.
    pkgs="$pkgs catatonit python3-yaml"
    # The Python client's tests (tests/python/run.sh): Debian's python3 makes a
    # venv that sees the system pytest, and pip installs python/ into it offline.
    pkgs="$pkgs python3 python3-venv python3-pytest"
    # The Python package builds with setuptools and wheel, Debian's, so that
    # `pip install --no-build-isolation ./python` needs no package index; the
    # python_mypy test checks the package with Debian's mypy (--strict).
    pkgs="$pkgs python3-setuptools python3-wheel python3-mypy"
    # scripts/wheel.sh (the python_wheel test) builds the wheel with
    # Debian's own pip (`/usr/bin/python3 -m pip wheel`), not a venv's.
    pkgs="$pkgs python3-pip"
    # The Wireshark dissector's test (tests/wireshark/run.py) decodes the
    # emulator's captures with Debian's tshark.
    pkgs="$pkgs tshark"
    # The web page's browser tests (tests/browser/run.sh): Debian's Chromium,
    # headless, driven through WebDriver by chromium-driver and Debian's
    # python3-selenium.
    pkgs="$pkgs chromium chromium-driver python3-selenium"
    # The libFuzzer harnesses (tests/fuzz, the fuzz build of scripts/test.sh):
    # clang, and its fuzzer and sanitizer runtime, which clang only recommends.
    # The runtime's package carries clang's major version: the clang-N that the
    # clang package depends on (Debian 12: 14).
    clang_major=$(apt-cache depends clang 2>/dev/null |
        sed -n 's/^ *Depends: clang-\([0-9][0-9]*\)$/\1/p' | head -n 1)
    pkgs="$pkgs clang libclang-rt-${clang_major:-14}-dev"
    # The CAN tests (tests/can/run.sh): where the host kernel has no vcan, QEMU
    # boots Debian's kernel with it; xz unpacks that kernel, iproute2's ip and
    # tc make the buses. The kernel and busybox themselves are only downloaded,
    # by tests/can/vm-image.sh. The VM runs amd64 programs: amd64 hosts only.
    if [ "$(dpkg --print-architecture)" = amd64 ]; then
        pkgs="$pkgs qemu-system-x86 xz-utils iproute2"
    fi
    # The firstrun test (tests/firstrun/run.sh) follows the README in a
    # fresh Debian 12 root that debootstrap builds; git clones the tree
    # into it.
    pkgs="$pkgs debootstrap git"
fi

if [ "$print" = 1 ]; then
    printf '%s\n' $pkgs
    exit 0
fi

missing=""
for p in $pkgs; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null |
        grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
    sudo=""
elif command -v sudo >/dev/null 2>&1; then
    sudo="sudo"
else
    echo "deps.sh: need root (or sudo) to install:$missing" >&2
    exit 1
fi
echo "deps.sh: missing:$missing" >&2
echo "deps.sh: apt-get update (the package lists)" >&2
$sudo apt-get update -q
# What apt-get will fetch and install, with what they pull in, before it
# does: the count, the download and the disk space.
# shellcheck disable=SC2086
LC_ALL=C $sudo apt-get install --no-install-recommends --assume-no \
    $missing 2>/dev/null |
    sed -n 's/^\([0-9][0-9]* upgraded, .*\)/deps.sh: \1/p
            s/^Need to get \(.*\)/deps.sh: to download: \1/p
            s/^After this operation, \(.*\)/deps.sh: \1/p' >&2 || true
echo "deps.sh: apt-get install (each download, then each package set up)" >&2
# shellcheck disable=SC2086
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q \
    -o Dpkg::Use-Pty=0 --no-install-recommends $missing
echo "deps.sh: done" >&2
