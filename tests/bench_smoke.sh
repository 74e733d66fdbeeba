#!/bin/sh
# Smoke test of wsgbench (tools/wsgbench/), two --quick runs:
#  1. against the wsgemu and wsgref it finds beside itself;
#  2. attached (--attach READY --pid PID, --no-fleet) to a wsgemu this
#     script starts, with every interface, so no row may be n/a either.
# Both include the script rows (a wsgemu --script of the bench's own each
# time, with tests/scripts/bench_echo.lua and bench_pd.lua): about 5 s;
# and the GCL rows (POS? on a wsgemu --text-interface on of the bench's
# own against 43h on another): under a second.
# It checks that each run ends with status 0 and that every row of the
# table is there with a number in the emulator column (and the reference
# column where the row has one). No figure is compared with its target:
# machines are noisy, and the bench itself never fails on a missed target.
#
# Usage: bench_smoke.sh PATH/TO/wsgbench
# Environment: WSG_TEST_TIME_SCALE (a number >= 1, default 1) multiplies the
#   wait for the ready line, as in the C tests (tests/integration/emu.h).
set -u

bench=${1:?usage: bench_smoke.sh PATH/TO/wsgbench}
emu=$(dirname "$1")/../wsgemu
out=$(mktemp)
dir=$(mktemp -d)
emu_pid=
# shellcheck disable=SC2317 # run by the EXIT trap
cleanup() {
    # Only the emulator this script started, by its PID.
    if [ -n "$emu_pid" ]; then
        kill "$emu_pid" 2>/dev/null
        wait "$emu_pid" 2>/dev/null
    fi
    rm -f "$out"
    rm -rf "$dir"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

fail=0
num='-\{0,1\}[0-9][0-9]*\(\.[0-9]*\)\{0,1\}'
# row label (a basic regular expression, as at the start of the line) and
# whether the reference column must hold a number too (else it is "-").
check() {
    label=$1
    ref=$2
    if [ "$ref" = yes ]; then
        want="^$label  *$num  *$num "
    else
        want="^$label  *$num  *- "
    fi
    if ! grep -q "$want" "$out"; then
        echo "FAIL: no row with numbers: $label" >&2
        fail=1
    fi
}

# The rows of one emulator and the reference.
check_rows() {
    for t in TCP UDP pty; do
        for f in median p99 max; do
            check "$t latency $f (us)" yes
        done
    done
    check "TCP pipelined, 32 in flight (1/s)" yes
    for f in p50 p99 max; do
        check "43h stream 10 ms jitter $f (us)" yes
    done
    check "43h stream intervals (count)" yes
    check "idle wakes/s" yes
    check "idle CPU % of one core" yes
    check "1 s stream, idle: wakes/s" yes
    check "moving: model steps/s" no
    check "moving: step overruns" no
    check "moving: CPU % of one core" no
    check "x100: home+grasp+release wall (ms)" no
    check "x100: same, simulated (s)" no
    check "x100: speed-up (simulated/wall)" no
    check "RSS (MiB)" yes
    check "peak RSS, VmHWM (MiB)" yes
    check_script
    check_gcl
}

# The script rows: the round trip's reference column is the 43h.
check_script() {
    check "script B0h round trip median (us)" yes
    check "script B0h round trip p99 (us)" yes
    check "script in cmd.read: timer wakes" no
    for r in 250 500 1000 2000; do
        check "script PD $r Hz: answers/s" no
        check "script PD $r Hz: answered (%)" no
        check "script PD $r Hz: overruns" no
    done
    check "script PD: top rate sustained (1/s)" no
}

# The GCL rows: the reference column is the binary 43h.
check_gcl() {
    check "GCL POS? round trip median (us)" yes
    check "GCL POS? round trip p99 (us)" yes
}

check_fleet() {
    check "fleet 20: idle wakes/s" no
    check "fleet 20: idle CPU % of one core" no
    check "fleet 20: RSS (MiB)" no
    check "fleet 20: homing all (s)" no
    for m in 2 20; do
        check "fleet $m/20 moving: CPU %" no
        check "fleet $m/20 moving: steps/s" no
        check "fleet $m/20 moving: overruns" no
    done
    check "fleet CPU all / CPU 2 moving" no
}

# The MuJoCo plant's rows, unless the bench says the emulator was built
# without it (there are none then).
check_physics() {
    if grep -q 'built without MuJoCo' "$dir/bench.err"; then
        return
    fi
    check "builtin holding: CPU % of one core" no
    check "mujoco holding: CPU % of one core" no
    check "mujoco holding: model steps/s" no
    check "mujoco holding: step overruns" no
    check "mujoco holding / builtin moving CPU" no
    check "mujoco x100: cycle wall (ms)" no
    check "mujoco x100: speed-up" no
}

check_measured() {
    if grep -q 'n/a' "$out"; then
        echo "FAIL: a figure was not measured (n/a) in the $1 run" >&2
        fail=1
    fi
}

# 1. The bench starts the emulator.
"$bench" --quick >"$out" 2>"$dir/bench.err"
rc=$?
cat "$out"
cat "$dir/bench.err" >&2
if [ "$rc" -ne 0 ]; then
    echo "FAIL: wsgbench --quick exited with status $rc" >&2
    exit 1
fi
check_rows
check_fleet
check_physics
check_measured started

# 2. Attached to a running emulator. Its UDP answers go to this port,
# which the bench binds: one of 20000..29999, below the usual ephemeral
# range, picked by this shell's PID.
port=$((20000 + $$ % 10000))
"$emu" --tcp 127.0.0.1:0 --udp "127.0.0.1:0:$port" --pty "$dir/x" \
    --control 127.0.0.1:0 >"$dir/ready" 2>"$dir/emu.err" </dev/null &
emu_pid=$!
line=
i=0
# Up to 10 s, scaled, in tenths.
tenths=$(awk -v k="${WSG_TEST_TIME_SCALE:-1}" 'BEGIN { printf "%d", 100 * k }')
while [ "$i" -lt "$tenths" ]; do
    if [ -s "$dir/ready" ] && [ "$(wc -l <"$dir/ready")" -ge 1 ]; then
        line=$(head -n 1 "$dir/ready")
        break
    fi
    kill -0 "$emu_pid" 2>/dev/null || break
    sleep 0.1 2>/dev/null || sleep 1
    i=$((i + 1))
done
case $line in
ready\ *) ;;
*)
    echo "FAIL: $emu gave no ready line (\"$line\")" >&2
    cat "$dir/emu.err" >&2
    exit 1
    ;;
esac
echo "attaching to: $line (pid $emu_pid)"

"$bench" --quick --no-fleet --attach "$line" --pid "$emu_pid" >"$out"
rc=$?
cat "$out"
if [ "$rc" -ne 0 ]; then
    echo "FAIL: wsgbench --quick --attach exited with status $rc" >&2
    exit 1
fi
if ! grep -q "^wsgbench .*: attached wsgemu (pid $emu_pid) vs wsgref" "$out"; then
    echo "FAIL: the header does not name the attached emulator" >&2
    fail=1
fi
check_rows
check_measured attached
if grep -q '^fleet' "$out"; then
    echo "FAIL: fleet rows despite --no-fleet" >&2
    fail=1
fi

# The emulator must have lived through it, and end as it should.
if ! kill -0 "$emu_pid" 2>/dev/null; then
    echo "FAIL: the attached emulator is gone" >&2
    fail=1
fi
kill "$emu_pid" 2>/dev/null
wait "$emu_pid"
rc=$?
emu_pid=
if [ "$rc" -ne 0 ]; then
    echo "FAIL: the attached emulator ended with status $rc" >&2
    cat "$dir/emu.err" >&2
    fail=1
fi

[ "$fail" -eq 0 ] && echo "bench_smoke: every row measured, started and attached"
exit "$fail"
