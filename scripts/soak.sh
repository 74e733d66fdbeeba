#!/bin/bash
# soak.sh: check that the test suite holds on a loaded machine. Runs ctest
# N times in a row in the normal build and N times in the ASan/UBSan build
# (slower, so the timing of everything that is not in lockstep shifts
# further) while a CPU hog keeps every core busy beside it (stress-ng where
# it is installed, else one shell busy loop per core), as other builds and
# test runs do on a shared machine. The tests' waits are bounds, not
# expectations (tests/integration/emu.h), so they must pass like this every
# time; a run that fails is a flake to fix. Each run's ctest output is kept
# in BUILD/soak/run-I.log; every run's result and a final "N passed, M
# failed" line are printed. The hog is stopped when the script ends,
# however it ends.
#
# Usage: scripts/soak.sh [N] [CTEST_ARGS...]
#   N runs (default 5); CTEST_ARGS go to each ctest run, e.g.
#   -E 'can|container|package' to leave out the slow VM, container and
#   package tests.
# Environment: WSG_SOAK_BUILDS the build trees, in turn (default "build
#   build-asan", made with cmake -B build -DWSG_SANITIZE=OFF and cmake -B
#   build-asan -DWSG_SANITIZE=ON, each then cmake --build; as
#   scripts/test.sh makes them); a tree configured with WSG_SANITIZE=ON
#   runs with the sanitizer options of scripts/test.sh;
#   WSG_SOAK_HOGS how many busy loops (default: one per core; 0: none).
# Exit status: 0 every run passed, 1 one failed, 2 usage.
set -u
cd "$(dirname "$0")/.." || exit 2

runs=5
if [ $# -gt 0 ] && [[ $1 =~ ^[0-9]+$ ]]; then
    runs=$1
    shift
fi
if [ "$runs" -lt 1 ]; then
    echo "usage: scripts/soak.sh [N] [CTEST_ARGS...]  (N >= 1)" >&2
    exit 2
fi
builds=${WSG_SOAK_BUILDS:-build build-asan}
for build in $builds; do
    if [ ! -f "$build/CTestTestfile.cmake" ]; then
        echo "soak.sh: no build in $build: scripts/test.sh makes build and" \
             "build-asan (or set WSG_SOAK_BUILDS)" >&2
        exit 2
    fi
done
hogs=${WSG_SOAK_HOGS:-$(nproc 2>/dev/null || echo 2)}

hog_pids=()
# shellcheck disable=SC2317 # run by the traps
stop_hog() {
    local p
    # Only the hog processes this script started, by their PIDs.
    for p in "${hog_pids[@]}"; do
        kill "$p" 2>/dev/null
    done
    for p in "${hog_pids[@]}"; do
        wait "$p" 2>/dev/null
    done
    hog_pids=()
}
trap stop_hog EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

if [ "$hogs" -gt 0 ]; then
    if command -v stress-ng >/dev/null 2>&1; then
        stress-ng --cpu "$hogs" --quiet &
        hog_pids+=($!)
        echo "soak.sh: CPU hog: stress-ng --cpu $hogs (pid ${hog_pids[*]})"
    else
        for ((i = 0; i < hogs; i++)); do
            # A subshell spinning on a builtin: a whole core, no forks.
            (while :; do :; done) &
            hog_pids+=($!)
        done
        echo "soak.sh: CPU hog: $hogs busy loops (pids ${hog_pids[*]})"
    fi
else
    echo "soak.sh: no CPU hog (WSG_SOAK_HOGS=0)"
fi

passed=0
failed=0
for build in $builds; do
    logs=$build/soak
    mkdir -p "$logs"
    san=()
    # As scripts/test.sh runs the sanitizer build: findings are fatal.
    if grep -q '^WSG_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null; then
        san=(env ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
             UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1)
    fi
    for ((r = 1; r <= runs; r++)); do
        log=$logs/run-$r.log
        t0=$(date +%s)
        st=0
        "${san[@]}" ctest --test-dir "$build" --output-on-failure "$@" \
            >"$log" 2>&1 || st=$?
        t1=$(date +%s)
        if [ "$st" = 0 ]; then
            passed=$((passed + 1))
            echo "$build run $r/$runs: passed, $((t1 - t0)) s ($(grep -m1 'tests passed' "$log"))"
        else
            failed=$((failed + 1))
            echo "$build run $r/$runs: FAILED (ctest status $st), $((t1 - t0)) s, log $log:"
            # ctest's list of the failed tests, one per line.
            sed -n '/The following tests FAILED:/,$p' "$log" | sed 1d |
                grep -E '^[[:space:]]+[0-9]+ - ' || echo "  (no test list: see the log)"
        fi
    done
done
echo "soak.sh: $passed passed, $failed failed"
[ "$failed" = 0 ]
