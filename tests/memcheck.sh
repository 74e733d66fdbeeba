#!/bin/bash
# memcheck.sh: run integration tests with every program they start (the
# daemon, and wsgctl in integ_wsgctl) under valgrind's memcheck, through
# WSG_TEST_WRAPPER (see spawn() in tests/integration/emu.c). Any invalid
# access, use of uninitialised memory, or definite or indirect leak makes
# valgrind end the program with status 99: the test sees that status when
# it stops the daemon and fails; valgrind's reports are also collected in
# files and any report at all fails this script.
#
# Usage: memcheck.sh WSGEMU INTEG_DIR [TEST[:TRANSPORT]...]
#   (integ_script and integ_gcl take their part where the others take a
#   transport)
#   INTEG_DIR holds the integration test programs; without TESTs, the list
#   below. Exit status: 0 clean, 1 a test failed or valgrind reported
#   something, 77 no valgrind here (skipped), 2 usage.
# Environment: WSGCTL as for integ_wsgctl; WSG_TEST_TIME_SCALE (default
#   here 10) multiplies the tests' waits.
set -eu

ME=memcheck.sh
[ $# -ge 2 ] || { echo "usage: $ME WSGEMU INTEG_DIR [TEST[:TRANSPORT]...]" >&2; exit 2; }
EXE=$1
DIR=$2
shift 2

# The tests that hold under valgrind (the daemon runs some 20-50 times
# slower; these were checked to pass under it, each in under 50 s, most of
# it the quiet windows, ten times as long here). Left
# out: integ_hostile (it bounds the daemon's RSS, which under valgrind is
# valgrind's own; and it floods the daemon against deadlines) and the `can`
# test (it runs in a VM without valgrind). scenarios is the shell script
# tests/scenarios/scenarios.sh, in lockstep, run with wsgctl ($WSGCTL).
if [ $# = 0 ]; then
    set -- \
        integ_basic:tcp integ_basic:udp integ_basic:pty \
        integ_motion:tcp integ_motion:udp integ_motion:pty \
        integ_disconnect:tcp integ_disconnect:udp integ_disconnect:pty \
        integ_streams:tcp integ_streams:udp integ_streams:pty \
        integ_udp integ_pty integ_control integ_settings integ_log \
        integ_latency integ_together integ_wsgctl integ_fleet integ_fingers \
        integ_web \
        integ_webforms integ_webscripts integ_webevents integ_webhost \
        integ_webhostile \
        integ_script:api integ_script:ifaces integ_script:speed \
        integ_script:lifecycle integ_script:sandbox integ_script:lockstep \
        integ_script:startup integ_script:dialect \
        integ_gcl:commands integ_gcl:framing integ_gcl:rules \
        integ_gcl:fleet integ_gcl:log \
        integ_physics:shapes integ_physics:pull integ_physics:scene \
        integ_physics:determinism integ_physics:fingers scenarios
fi

if ! command -v valgrind >/dev/null 2>&1; then
    echo "$ME: no valgrind here (scripts/deps.sh --test installs it): skipped"
    exit 77
fi

LOGS=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-memcheck.XXXXXX")
trap 'rm -rf "$LOGS"' EXIT
export WSG_TEST_WRAPPER="valgrind --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect --track-fds=no -q --log-file=$LOGS/vg.%p"
# Every wait of the tests ten times as long (tests/integration/emu.h): the
# programs run far slower under valgrind, more so on a loaded machine.
export WSG_TEST_TIME_SCALE=${WSG_TEST_TIME_SCALE:-10}

passed=0 failed=0 skipped=0 reports=0
for t in "$@"; do
    name=${t%%:*}
    tp=${t#*:}
    [ "$tp" != "$t" ] || tp=""
    echo "=== $name${tp:+ $tp}"
    st=0
    t0=$(date +%s)
    # shellcheck disable=SC2086 # no transport: no argument
    # A bound on a hang only: a loaded machine may take twice as long.
    if [ "$name" = scenarios ]; then
        timeout -k 5 300 bash "$(dirname "$0")/scenarios/scenarios.sh" \
            "$EXE" "${WSGCTL:?WSGCTL: wsgctl for the scenarios}" \
            </dev/null || st=$?
    else
        timeout -k 5 300 "$DIR/$name" "$EXE" $tp </dev/null || st=$?
    fi
    echo "--- $name${tp:+ $tp}: status $st, $(($(date +%s) - t0)) s"
    case $st in
    0) passed=$((passed + 1)) ;;
    77) skipped=$((skipped + 1)) ;;
    *) failed=$((failed + 1)); echo "$ME: $name${tp:+ $tp} FAILED (status $st)" ;;
    esac
    for f in "$LOGS"/vg.*; do
        [ -e "$f" ] || continue
        if [ -s "$f" ]; then
            echo "$ME: valgrind reported, in $name${tp:+ $tp} (pid ${f##*.}):"
            cat "$f"
            reports=$((reports + 1))
        fi
        rm -f "$f"
    done
done
echo "memcheck: $passed passed, $failed failed, $skipped skipped; $reports valgrind reports"
[ "$failed" = 0 ] && [ "$reports" = 0 ]
