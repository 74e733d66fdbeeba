#!/bin/bash
# run.sh: run the CAN tests (integ_can and the protocol suite over CAN) on a
# real SocketCAN bus, the first way that works here:
#   native  the host has the interface (vcan0), or can create it (root, a
#           kernel with vcan): the tests run right here;
#   vm      QEMU boots Debian's kernel with vcan (vm-image.sh prepares it)
#           and a busybox initramfs holding wsgemu and the test programs;
#           one boot runs them all, their statuses come back on a serial
#           port;
#   skip    neither: exit 77 with the reason (ctest shows "skipped").
# Where it can (in the VM always; natively as root with tc), it also makes
# a slow bus: a second vcan whose queue a tbf qdisc keeps short and drains
# at 64 kbit/s, so that the daemon's sends meet a full queue (ENOBUFS) and
# must be retried; integ_can tests it when WSG_TEST_CAN_SLOW_IFACE names it.
# See docs/can-testing.md.
#
# Usage: run.sh [--mode auto|native|vm] [--cache DIR] [--test-timeout S]
#              WSGEMU TEST...
#   Each TEST runs as `TEST WSGEMU can`, one after the other, and is killed
#   after S seconds (default 120). The whole run takes at most
#   600 + 60 + S * (number of TESTs) seconds: 600 to prepare the VM image
#   (a download on the first run), 60 to boot and stop the VM.
# Exit status: 0 all passed (a test's own 77 counts as skipped), 1 one
#   failed or the VM broke down, 77 no CAN bus to be had here.
# Environment:
#   WSG_CAN_MODE          as --mode (default auto: native, else vm)
#   WSG_CAN_VM_CACHE      as --cache (default ~/.cache/wsgemu/can-vm)
#   WSG_CAN_REQUIRE=1     "no CAN bus here" fails (exit 1) instead of 77
#   WSG_CAN_VM_ACCEL      tcg or kvm (default: kvm only where the CPU shows
#                         vmx/svm and /dev/kvm is usable)
#   WSG_TEST_CAN_IFACE    the interface (default vcan0)
#   WSG_TEST_TIME_SCALE   multiplies the tests' waits, in the VM too
set -eu

ME=run.sh
HERE=$(cd "$(dirname "$0")" && pwd)
MODE=${WSG_CAN_MODE:-auto}
CACHE=${WSG_CAN_VM_CACHE:-}
TEST_TIMEOUT=120
IMAGE_TIMEOUT=600
IFACE=${WSG_TEST_CAN_IFACE:-vcan0}
SLOW_IFACE=wsgcanslow
# The slow bus: 500 frames/s (a classic frame is 16 bytes to the qdisc), a
# queue of 10 frames, a burst of 4.
SLOW_QDISC="tbf rate 64kbit burst 64 limit 160"

while [ $# -gt 0 ]; do
    case $1 in
    --mode) MODE=$2; shift 2 ;;
    --cache) CACHE=$2; shift 2 ;;
    --test-timeout) TEST_TIMEOUT=$2; shift 2 ;;
    --) shift; break ;;
    -*) echo "$ME: unknown option $1" >&2; exit 2 ;;
    *) break ;;
    esac
done
[ $# -ge 2 ] || { echo "usage: $ME [--mode auto|native|vm] [--cache DIR] [--test-timeout S] WSGEMU TEST..." >&2; exit 2; }
EXE=$1
shift
for f in "$EXE" "$@"; do
    [ -x "$f" ] || { echo "$ME: $f: not an executable" >&2; exit 2; }
done

cannot_run() {
    echo "$ME: cannot run the CAN tests here: $*"
    if [ "${WSG_CAN_REQUIRE:-0}" = 1 ]; then
        echo "$ME: WSG_CAN_REQUIRE=1: that is a failure"
        exit 1
    fi
    exit 77
}

# Count the statuses and say the verdict: report NAME STATUS, then summary.
passed=0 failed=0 skipped=0
report() {
    case $2 in
    0) passed=$((passed + 1)) ;;
    77) skipped=$((skipped + 1)) ;;
    *) failed=$((failed + 1)); echo "$ME: $1 FAILED (status $2)" ;;
    esac
}
summary() {
    echo "can ($1): $passed passed, $failed failed, $skipped skipped"
    [ "$failed" = 0 ] || exit 1
    # The bus was there: tests that all skip have not tested anything.
    [ "$passed" -gt 0 ] || { echo "$ME: no test ran on the bus"; exit 1; }
    exit 0
}

# ---------------------------------------------------------------- native ---
CREATED=""
SLOW_CREATED=""
# shellcheck disable=SC2317 # called from the EXIT trap
cleanup_native() {
    [ -z "$CREATED" ] || ip link del dev "$IFACE" 2>/dev/null || true
    [ -z "$SLOW_CREATED" ] || ip link del dev "$SLOW_IFACE" 2>/dev/null || true
}
native_bus() {
    if [ ! -e "/sys/class/net/$IFACE" ]; then
        [ "$(id -u)" = 0 ] && command -v ip >/dev/null 2>&1 || return 1
        modprobe vcan 2>/dev/null || true
        ip link add dev "$IFACE" type vcan 2>/dev/null || return 1
        CREATED=1
    fi
    [ "$(cat "/sys/class/net/$IFACE/type")" = 280 ] || return 1 # ARPHRD_CAN
    if [ $(($(cat "/sys/class/net/$IFACE/flags") & 1)) = 0 ]; then
        ip link set up dev "$IFACE" 2>/dev/null || return 1
    fi
    return 0
}

# Root with tc and sch_tbf: the slow bus, ours alone, removed at the end.
native_slow_bus() {
    [ "$(id -u)" = 0 ] && command -v tc >/dev/null 2>&1 || return 1
    [ ! -e "/sys/class/net/$SLOW_IFACE" ] || return 1
    ip link add dev "$SLOW_IFACE" type vcan 2>/dev/null || return 1
    SLOW_CREATED=1
    # shellcheck disable=SC2086
    tc qdisc add dev "$SLOW_IFACE" root $SLOW_QDISC 2>/dev/null &&
        ip link set up dev "$SLOW_IFACE"
}

run_native() {
    local t st
    echo "$ME: native SocketCAN on $IFACE"
    export WSG_TEST_CAN_IFACE=$IFACE
    if native_slow_bus; then
        echo "$ME: slow bus $SLOW_IFACE: $SLOW_QDISC"
        export WSG_TEST_CAN_SLOW_IFACE=$SLOW_IFACE
    else
        echo "$ME: no slow bus (needs root, tc and sch_tbf)"
    fi
    for t in "$@"; do
        echo "=== ${t##*/}"
        st=0
        timeout -k 5 "$TEST_TIMEOUT" "$t" "$EXE" can </dev/null || st=$?
        report "${t##*/}" "$st"
    done
    summary native
}

QPID=""
WORK=""
# shellcheck disable=SC2317 # the EXIT trap
cleanup() {
    [ -z "$QPID" ] || kill "$QPID" 2>/dev/null || true
    [ -z "$WORK" ] || rm -rf "$WORK"
    cleanup_native
}
trap cleanup EXIT
trap 'exit 130' INT TERM

if [ "$MODE" = auto ] || [ "$MODE" = native ]; then
    if native_bus; then
        run_native "$@"
    fi
    [ "$MODE" = native ] && cannot_run "no $IFACE, and it cannot be created (root and a kernel with vcan are needed)"
fi
[ "$MODE" = auto ] || [ "$MODE" = vm ] || { echo "$ME: --mode auto, native or vm" >&2; exit 2; }

# -------------------------------------------------------------------- VM ---
command -v qemu-system-x86_64 >/dev/null 2>&1 ||
    cannot_run "no $IFACE and no qemu-system-x86_64 (scripts/deps.sh --test installs qemu-system-x86)"
command -v ldd >/dev/null 2>&1 || cannot_run "ldd missing"

st=0
IMG=$(timeout -k 5 "$IMAGE_TIMEOUT" bash "$HERE/vm-image.sh" ${CACHE:+"$CACHE"}) || st=$?
case $st in
0) ;;
77) cannot_run "no VM image (see above)" ;;
124 | 137) echo "$ME: preparing the VM image took over $IMAGE_TIMEOUT s"; exit 1 ;;
*) echo "$ME: preparing the VM image failed"; exit 1 ;;
esac
CACHE_DIR=$(dirname "$IMG")
# A concurrent vm-image.sh replaces images under an exclusive lock: hold a
# shared one while this image is read.
exec 8>"$CACHE_DIR/.lock"
flock -s -w 600 8 || { echo "$ME: cache locked"; exit 1; }
[ -f "$IMG/.ready" ] || { echo "$ME: $IMG went away; run again"; exit 1; }
KVER=$(cat "$IMG/kver")

WORK=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-can-vm.XXXXXX")

# The initramfs: busybox, the modules, the programs with their libraries
# at the paths ldd names (the dynamic loader among them).
R=$WORK/root
mkdir -p "$R/bin" "$R/proc" "$R/sys" "$R/dev" "$R/tmp" "$R/wsg" "$R/lib/modules"
cp "$IMG/busybox" "$R/bin/busybox"
cp -a "$IMG/lib/modules/$KVER" "$R/lib/modules/"
add_program() { # add_program FILE NAME
    local lib
    cp "$1" "$R/wsg/$2"
    for lib in $(ldd "$1" 2>/dev/null | grep -oE '/[^ ]+' || true); do
        if [ ! -e "$lib" ] || [ -e "$R$lib" ]; then
            continue
        fi
        mkdir -p "$R$(dirname "$lib")"
        cp -L "$lib" "$R$lib"
    done
}
add_program "$EXE" wsgemu
# iproute2's tc makes the slow bus (busybox's tc cannot add qdiscs).
TC=$(command -v tc 2>/dev/null || true)
if [ -n "$TC" ]; then
    mkdir -p "$R/wsg/bin"
    add_program "$TC" bin/tc
else
    echo "$ME: no tc here (iproute2): no slow bus in the VM"
fi
: >"$R/wsg/tests"
for t in "$@"; do
    add_program "$t" "${t##*/}"
    echo "${t##*/}" >>"$R/wsg/tests"
done
echo "$TEST_TIMEOUT" >"$R/wsg/timeout"
# The tests' time scale (tests/integration/emu.h), as the host's tests have
# it: natively the tests inherit it.
echo "${WSG_TEST_TIME_SCALE:-}" >"$R/wsg/time-scale"
echo "$IFACE" >"$R/wsg/iface"
echo "$SLOW_IFACE $SLOW_QDISC" >"$R/wsg/slow"

# PID 1: bring up the bus, run every test with its output on the second
# serial port (the kernel's console is the first), report each status
# there, power off.
cat >"$R/init" <<'EOF'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin HOME=/tmp TMPDIR=/tmp
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
out=/dev/ttyS1
stty -F $out raw -echo 2>/dev/null
say() { echo "$*" >$out; }
bail() { say "@@wsg-can-vm broken $*"; sync; poweroff -f; }
iface=$(cat /wsg/iface)
for m in can can-raw vcan; do modprobe $m || bail "modprobe $m"; done
ip link set lo up
ip link add dev "$iface" type vcan || bail "ip link add $iface"
ip link set up dev "$iface" || bail "ip link set up $iface"
export WSG_TEST_CAN_IFACE="$iface"
scale=$(cat /wsg/time-scale)
[ -z "$scale" ] || export WSG_TEST_TIME_SCALE="$scale"
read -r slow qdisc </wsg/slow
if [ -x /wsg/bin/tc ] && modprobe sch_tbf && ip link add dev $slow type vcan &&
    /wsg/bin/tc qdisc add dev $slow root $qdisc && ip link set up dev $slow; then
    export WSG_TEST_CAN_SLOW_IFACE=$slow
    say "slow bus $slow: $qdisc"
fi
t=$(cat /wsg/timeout)
cd /tmp
while read -r name; do
    say "=== $name"
    read -r t0 _ </proc/uptime
    timeout -s KILL "$t" "/wsg/$name" /wsg/wsgemu can </dev/null >$out 2>&1
    st=$?
    read -r t1 _ </proc/uptime
    say "--- $name: status $st, $(awk "BEGIN { print $t1 - $t0 }") s"
    say "@@wsg-can-vm status $name $st"
done </wsg/tests
if [ -n "${WSG_TEST_CAN_SLOW_IFACE:-}" ]; then
    say "slow bus after the tests (drops are refused frames, sent again):"
    /wsg/bin/tc -s qdisc show dev $slow >$out 2>&1
fi
say "@@wsg-can-vm end"
sync
poweroff -f
EOF
chmod 755 "$R/init"
(cd "$R" && find . | "$R/bin/busybox" cpio -o -H newc 2>/dev/null) >"$WORK/initramfs" ||
    { echo "$ME: cannot build the initramfs"; exit 1; }

ACCEL=${WSG_CAN_VM_ACCEL:-}
if [ -z "$ACCEL" ]; then
    # /dev/kvm without vmx/svm (a nested, paravirtual KVM) runs a stock
    # kernel far slower than TCG, and faults: only real KVM is used.
    ACCEL=tcg
    if [ -r /dev/kvm ] && [ -w /dev/kvm ] && grep -qwE 'vmx|svm' /proc/cpuinfo; then
        ACCEL=kvm
    fi
fi
case $ACCEL in
kvm) ACCEL_ARGS="-accel kvm -cpu host" ;;
tcg) ACCEL_ARGS="-accel tcg" ;;
*) echo "$ME: WSG_CAN_VM_ACCEL must be tcg or kvm" >&2; exit 2 ;;
esac
# Boot, module loading and poweroff take some 3 s; then every test may use
# its whole timeout.
VM_TIMEOUT=$((60 + TEST_TIMEOUT * $#))

echo "$ME: booting $KVER in QEMU ($ACCEL) to run $# test programs on $IFACE"
T0=$(date +%s%N)
: >"$WORK/out"
: >"$WORK/console"
# Two CPUs: the daemon and the test run side by side, as on the host.
# shellcheck disable=SC2086
timeout -k 5 "$VM_TIMEOUT" qemu-system-x86_64 \
    -machine pc $ACCEL_ARGS -smp 2 -m 256 \
    -nodefaults -no-user-config -display none -no-reboot -nic none \
    -kernel "$IMG/kernel" -initrd "$WORK/initramfs" \
    -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" \
    -serial "file:$WORK/console" -serial "file:$WORK/out" \
    </dev/null >"$WORK/qemu.log" 2>&1 &
QPID=$!
QST=0
wait "$QPID" || QST=$?
QPID=""
T1=$(date +%s%N)
SECS=$(((T1 - T0) / 1000000000)).$(((T1 - T0) / 100000000 % 10))

grep -av '^@@wsg-can-vm ' "$WORK/out" || true
while read -r _ _ name st; do
    report "$name" "$st"
done < <(grep -a '^@@wsg-can-vm status ' "$WORK/out" | tr -d '\r')
echo "$ME: the VM ran for $SECS s"
if ! grep -aq '^@@wsg-can-vm end' "$WORK/out"; then
    if grep -aq '^@@wsg-can-vm broken' "$WORK/out"; then
        echo "$ME: VM setup failed: $(grep -a '^@@wsg-can-vm broken' "$WORK/out" | cut -d' ' -f3-)"
    elif [ "$QST" = 124 ] || [ "$QST" = 137 ]; then
        echo "$ME: the VM did not finish within $VM_TIMEOUT s"
    else
        echo "$ME: the VM ended early (qemu status $QST)"
    fi
    echo "$ME: qemu said:"
    tail -n 20 "$WORK/qemu.log"
    echo "$ME: the VM's console said:"
    tail -n 40 "$WORK/console"
    failed=$((failed + 1))
fi
summary "vm, $ACCEL"
