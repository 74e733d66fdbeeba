#!/bin/bash
# test.sh: build wsgemu three times and run the tests of each build, with
# warnings as errors (-DWSG_WERROR=ON: the project's own builds only; a
# user's or a distribution's build keeps them warnings):
#   build       the normal build (RelWithDebInfo), all of ctest, including
#               `memcheck` (the daemon under valgrind over the integration
#               tests that hold under it, tests/memcheck.sh);
#   build-asan  -DWSG_SANITIZE=ON: everything built with AddressSanitizer and
#               UndefinedBehaviorSanitizer, all of ctest again (memcheck is
#               not registered there: valgrind cannot run ASan programs).
#               Any sanitizer finding, in a test or in the daemon a test
#               started, aborts that program, and the test fails;
#   build-fuzz  -DWSG_FUZZ=ON with clang: only the libFuzzer harnesses
#               (target fuzz_harnesses) and ctest's fuzz label: the seeds
#               and regression inputs through each, then each fuzzed for
#               60 s (WSG_FUZZ_SECONDS) from a copy of the seed corpus in
#               build-fuzz (tests/fuzz/run.sh). A finding fails the test
#               and is kept in build-fuzz/tests/fuzz/findings, hex-dumped
#               in the log, with the command that adds it to
#               tests/fuzz/regressions. Without clang or its libFuzzer
#               runtime, the fuzz tests are skipped (exit 77) and say why.
# Before those, three builds that are only compiled, each of the whole tree
# with warnings as errors, so that no build type or compiler a user may
# pick fails on a warning: build-debug (Debug) and build-release (Release)
# with the default compiler (gcc), build-clang (RelWithDebInfo) with clang
# where it is installed.
# Every run always happens; the summary at the end says which failed, and
# the exit status is non-zero if any did. Run scripts/deps.sh --test first.
# Usage: scripts/test.sh [CTEST_ARGS...]   (passed to every ctest run, e.g.
#   -R integ_basic or -LE can)
set -eu
cd "$(dirname "$0")/.."

jobs=$(nproc 2>/dev/null || echo 2)
results=()
failed=0

# run NAME DIR [CMAKE_ARGS...]: configure, build and test one build tree;
# $build_target (empty: everything) is what is built, $ctest_select more
# ctest arguments (empty: every test).
# $test_it (1) whether ctest runs after the build.
build_target=
ctest_select=()
test_it=1
run() {
    local name=$1 dir=$2 st=0 t0 t1
    local target=(${build_target:+--target "$build_target"})
    shift 2
    echo "=== test.sh: $name: configure and build $dir"
    t0=$(date +%s)
    if cmake -B "$dir" "$@" &&
        cmake --build "$dir" --parallel "$jobs" "${target[@]}"; then
        if [ "$test_it" = 1 ]; then
            echo "=== test.sh: $name: ctest in $dir"
            ctest --test-dir "$dir" --output-on-failure "${ctest_select[@]}" \
                "${ctest_args[@]}" || st=$?
            [ "$st" = 0 ] || st="ctest failed (status $st)"
        fi
    else
        st="build failed"
    fi
    t1=$(date +%s)
    if [ "$st" = 0 ]; then
        results+=("$name ($dir): passed, $((t1 - t0)) s")
    else
        results+=("$name ($dir): FAILED: $st, $((t1 - t0)) s")
        failed=1
    fi
}

ctest_args=("$@")

# compile NAME DIR [CMAKE_ARGS...]: configure and build only.
compile() {
    test_it=0
    run "$@"
    test_it=1
}
compile debug build-debug -DCMAKE_BUILD_TYPE=Debug -DWSG_WERROR=ON
compile release build-release -DCMAKE_BUILD_TYPE=Release -DWSG_WERROR=ON
if command -v clang >/dev/null 2>&1; then
    compile clang build-clang -DCMAKE_C_COMPILER=clang -DWSG_WERROR=ON
else
    results+=("clang (build-clang): skipped, no clang (scripts/deps.sh --test)")
fi

run normal build -DWSG_SANITIZE=OFF -DWSG_WERROR=ON

# Findings are fatal and say where: ASan aborts (abort_on_error), leaks
# are reported at exit (LeakSanitizer), UBSan stops at the first error with
# a stack trace. The daemon inherits this from the test that starts it; a
# daemon that aborts shows in its exit status, which the tests check.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
run sanitizers build-asan -DWSG_SANITIZE=ON -DWSG_WERROR=ON

# The libFuzzer harnesses, and nothing else: the rest of the project was
# tested above. Without clang, configured with the default compiler, the
# fuzz tests are registered only to say they skip.
fuzz_cc=()
if command -v clang >/dev/null 2>&1; then
    fuzz_cc=(-DCMAKE_C_COMPILER=clang)
fi
build_target=fuzz_harnesses
ctest_select=(-L fuzz)
run fuzz build-fuzz -DWSG_FUZZ=ON -DWSG_SANITIZE=OFF -DWSG_WERROR=ON \
    "${fuzz_cc[@]}"

echo "=== test.sh: summary"
for r in "${results[@]}"; do
    echo "  $r"
done
if [ "$failed" = 0 ]; then
    echo "test.sh: all passed"
else
    echo "test.sh: FAILED"
fi
exit "$failed"
