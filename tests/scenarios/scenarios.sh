#!/usr/bin/env bash
# The situations of the manual, scripted from a shell the way a test author
# would: wsgctl for the gripper, the control channel (bash's /dev/tcp) for
# the world and for time. Simulated time is paused and stepped, so every
# run sees exactly the same thing: no part, part lost, blocked axis, soft
# limit hit, FAST STOP, overheating in overdrive.
#
# Usage: scenarios.sh WSGEMU WSGCTL
# Environment: WSG_TEST_TIME_SCALE (a number >= 1, default 1) multiplies
#   every wait, as in the C tests (tests/integration/emu.h): a wait is a
#   bound on a hang, not an expectation. WSG_TEST_WRAPPER, if set, is the
#   command the daemon runs under (tests/memcheck.sh: valgrind), whose
#   exit status is checked at the end as the daemon's.
set -u

WSGEMU=$1
WSGCTL=$2
passed=0
failed=0
# The bound of every wait for an answer, in seconds.
wait_s=$(awk -v k="${WSG_TEST_TIME_SCALE:-1}" 'BEGIN { printf "%g", 5 * k }')

fail() {
    echo "FAIL: $*"
    failed=$((failed + 1))
}

ok() {
    echo "ok: $*"
    passed=$((passed + 1))
}

# shellcheck disable=SC2086 # the wrapper is a command line
coproc EMU { exec ${WSG_TEST_WRAPPER:-} "$WSGEMU" --tcp 127.0.0.1:0 --control 127.0.0.1:0; }
emu_pid=$EMU_PID
trap 'kill "$emu_pid" 2>/dev/null' EXIT
read -r -t "$wait_s" ready <&"${EMU[0]}" || { echo "no ready line"; exit 1; }
echo "$ready"
tcp=$(sed -n 's/.* tcp=\([^ ]*\).*/\1/p' <<<"$ready")
control=$(sed -n 's/.* control=\([^ ]*\).*/\1/p' <<<"$ready")
exec 5<>"/dev/tcp/${control%:*}/${control#*:}"

# One control command, its one-line answer on stdout.
ctl() {
    local line
    printf '%s\n' "$*" >&5
    read -r -t "$wait_s" line <&5 || { echo "error no answer to: $*"; return 1; }
    echo "$line"
}

gripper() { "$WSGCTL" --tcp "$tcp" --timeout "$wait_s" "$@"; }

# A motion in lockstep: wsgctl sends it and, once the gripper has accepted
# it (E_CMD_PENDING), advances simulated time by exactly MS through the
# control channel (--step), then waits for the final result. Simulated
# time moves by MS from the moment the command arrived, whatever the wall
# clock does meanwhile: every run sees the same thing, under load, ASan or
# valgrind alike. A command refused at once steps nothing. Its output in
# $out, its exit status in $st. Usage: stepped MS COMMAND [ARGS...]
# Simulated time given to each motion: more than the longest here takes
# (the whole stroke at 50 mm/s, with its ramps).
motion_ms=3000

stepped() {
    local ms=$1
    shift
    out=$(WSG_CONTROL=$control gripper --step "$ms" "$@" 2>&1)
    st=$?
}

expect() { # expect WHAT STATUS PATTERN
    if [ "$st" -eq "$2" ] && grep -q -- "$3" <<<"$out"; then
        ok "$1"
    else
        fail "$1: status $st, output: $out"
    fi
}

[ "$(ctl time pause)" = "ok paused" ] || fail "time pause"
t0=$(ctl time)
stepped "$motion_ms" home
expect "homing" 0 ""

# 1. No part: the fingers fall through the clamping travel.
stepped "$motion_ms" grasp 40 50
expect "no part: E_CMD_FAILED" 1 "E_CMD_FAILED"
out=$(gripper state)
st=$?
expect "no part: grasping state" 0 "NO_PART"

# 2. Part lost: held, then taken away.
stepped "$motion_ms" release 60 100
ctl part 40 >/dev/null
stepped "$motion_ms" grasp 40 50
expect "part held" 0 ""
ctl part none >/dev/null
ctl "time step 100" >/dev/null
out=$(gripper state)
st=$?
expect "part lost: grasping state" 0 "PART_LOST"
out=$(gripper -q stats)
st=$?
expect "part lost: statistics (total, no part, lost)" 0 "^2 1 1$"

# 3. Blocked axis: an obstacle in the way.
stepped "$motion_ms" release 80 100
ctl obstacle 50 >/dev/null
stepped "$motion_ms" move 20 100
expect "blocked axis: E_AXIS_BLOCKED" 1 "E_AXIS_BLOCKED"
out=$(gripper state)
st=$?
expect "blocked axis: flag" 0 "SF_BLOCKED_MINUS"
ctl obstacle none >/dev/null
ctl "time step 2000" >/dev/null

# 4. Soft limit hit: a grasp's clamping travel runs into the restricted
#    area with nothing to grasp: FAST STOP at the limit.
stepped "$motion_ms" move 80 100
gripper soft-limits 30 100 >/dev/null
stepped "$motion_ms" grasp 35 50
expect "soft limit: E_RANGE_ERROR" 1 "E_RANGE_ERROR"
out=$(gripper state)
st=$?
expect "soft limit: flags" 0 "SF_SOFT_LIMIT_MINUS.*SF_FAST_STOP"
gripper ack && gripper soft-limits clear
ctl "time step 10" >/dev/null

# 5. FAST STOP: movement refused until acknowledged.
gripper fast-stop
ctl "time step 10" >/dev/null
stepped "$motion_ms" move 60 100
expect "FAST STOP: motion refused" 1 "E_ACCESS_DENIED"
gripper ack
ctl "time step 10" >/dev/null
stepped "$motion_ms" move 60 100
expect "FAST STOP: acknowledged, motion again" 0 ""

# 6. Overheating in overdrive: 120 N held for 68 s of simulated time.
gripper overdrive on && gripper force-limit 120
ctl part 50 >/dev/null
stepped "$motion_ms" grasp 50 100
expect "overdrive grasp" 0 ""
ctl "time step 65000" >/dev/null
out=$(gripper state)
st=$?
expect "overheating: flags" 0 "SF_TEMP_WARNING SF_TEMP_FAULT"
out=$(gripper -q temperature)
st=$?
# The fault came at 75 degC after 66 s and turned the drive off: cooling
# since, still above the 70 degC at which the fault clears.
if [ "$st" -eq 0 ] && awk -v t="$out" 'BEGIN { exit !(t >= 70 && t < 75) }'; then
    ok "overheating: temperature $out degC"
else
    fail "overheating: temperature: status $st, $out"
fi
# Refused at once, with time standing still: the answer to a motion the
# gripper refuses comes before any step (an accepted one would wait for
# time to move: E_CMD_PENDING, then its result once stepped).
out=$(gripper move 90 100 2>&1)
st=$?
expect "overheating: movement refused" 1 "E_ACCESS_DENIED"

# Lockstep: simulated time moved by exactly what the scenario stepped, ten
# accepted motions of $motion_ms and the steps between them, whatever the
# wall clock did.
t=$(ctl time)
if awk -v t="${t#ok }" -v t0="${t0#ok }" -v m="$motion_ms" \
    'BEGIN { d = t - t0 - (10 * m + 67130) / 1000; exit !(d > -5e-7 && d < 5e-7) }'; then
    ok "lockstep: simulated time ${t#ok } s (${t0#ok } s at the pause)"
else
    fail "lockstep: simulated time: $t, ${t0#ok } s at the pause"
fi

# The daemon ends cleanly on SIGTERM (under valgrind: with no report).
exec 5>&-
kill -TERM "$emu_pid"
wait "$emu_pid"
st=$?
trap - EXIT
if [ "$st" -eq 0 ]; then
    ok "daemon stopped"
else
    fail "daemon stopped: exit status $st"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
