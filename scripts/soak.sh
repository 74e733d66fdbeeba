#!/bin/bash
# soak.sh: check that the test suite holds on a loaded machine. Runs the
# normal build's ctest N times in a row while a CPU hog keeps every core
# busy beside it (stress-ng where it is installed, else one shell busy loop
# per core), as other builds and test runs do on a shared machine. The
# tests' waits are bounds, not expectations (tests/integration/emu.h), so
# they must pass like this every time; a run that fails is a flake to fix.
# Each run's ctest output is kept in BUILD/soak/run-I.log; every run's result
# and a final "N passed, M failed" line are printed. The hog is stopped when
# the script ends, however it ends.
#
# Usage: scripts/soak.sh [N] [CTEST_ARGS...]
#   N runs (default 5); CTEST_ARGS go to each ctest run, e.g.
#   -E 'can|container|package' to leave out the slow VM, container and
#   package tests.
# Environment: WSG_SOAK_BUILD the build tree (default build, made with
#   cmake -B build -DWSG_SANITIZE=OFF && cmake --build build);
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
build=${WSG_SOAK_BUILD:-build}
if [ ! -f "$build/CTestTestfile.cmake" ]; then
    echo "soak.sh: no build in $build: cmake -B $build -DWSG_SANITIZE=OFF" \
         "&& cmake --build $build" >&2
    exit 2
fi
hogs=${WSG_SOAK_HOGS:-$(nproc 2>/dev/null || echo 2)}
logs=$build/soak
mkdir -p "$logs"

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
for ((r = 1; r <= runs; r++)); do
    log=$logs/run-$r.log
    t0=$(date +%s)
    st=0
    ctest --test-dir "$build" --output-on-failure "$@" >"$log" 2>&1 || st=$?
    t1=$(date +%s)
    if [ "$st" = 0 ]; then
        passed=$((passed + 1))
        echo "run $r/$runs: passed, $((t1 - t0)) s ($(grep -m1 'tests passed' "$log"))"
    else
        failed=$((failed + 1))
        echo "run $r/$runs: FAILED (ctest status $st), $((t1 - t0)) s, log $log:"
        # ctest's list of the failed tests, one per line.
        sed -n '/The following tests FAILED:/,$p' "$log" | sed 1d |
            grep -E '^[[:space:]]+[0-9]+ - ' || echo "  (no test list: see the log)"
    fi
done
echo "soak.sh: $passed passed, $failed failed"
[ "$failed" = 0 ]
