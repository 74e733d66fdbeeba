#!/bin/bash
# run.sh: fuzz one libFuzzer harness for a fixed time, the ctest tests
# fuzz_H_run (H = frames, commands, config, control, script, gcl, sse,
# match, fingers, fdev) of a -DWSG_FUZZ=ON build (clang).
# libFuzzer starts from a fresh copy of the committed seed corpus in the
# build tree and adds what it finds interesting to that copy only: the
# source tree is never written.
#
# A finding (a crash-*, leak-*, timeout-* or oom-* file that libFuzzer
# writes) fails the test. It is kept: copied into FINDINGS as
# HARNESS-KIND-HASH, hex-dumped into the log (so CI's output keeps it too),
# and the command that adds it to the regression inputs is printed; every
# build's fuzz_replay then runs it through every harness.
#
# Usage: run.sh HARNESS SEEDS WORKDIR FINDINGS REGRESSIONS SECONDS
#        run.sh --skip REASON
#   HARNESS the libFuzzer program; SEEDS the committed corpus directory;
#   WORKDIR where the corpus copy and libFuzzer's artifacts go (emptied
#   first); FINDINGS where findings are kept; REGRESSIONS the source tree's
#   tests/fuzz/regressions (only named in the printed command).
#   --skip: the harness could not be built here (no clang, or no libFuzzer
#   runtime): says why and exits 77.
# Exit status: 0 nothing found, 1 a finding or libFuzzer failed, 77 skipped,
#   2 usage.
set -u

if [ "${1:-}" = --skip ]; then
    echo "run.sh: skipped: ${2:-no libFuzzer harness in this build}"
    exit 77
fi
if [ $# -ne 6 ]; then
    echo "usage: run.sh HARNESS SEEDS WORKDIR FINDINGS REGRESSIONS SECONDS" >&2
    echo "       run.sh --skip REASON" >&2
    exit 2
fi
harness=$1
seeds=$2
work=$3
findings=$4
regressions=$5
seconds=$6
name=${harness##*/}

if [ ! -x "$harness" ] || [ ! -d "$seeds" ]; then
    echo "run.sh: no harness $harness or no seeds $seeds" >&2
    exit 2
fi
rm -rf "$work"
mkdir -p "$work/corpus" "$work/artifacts" "$findings" || exit 1
cp "$seeds"/* "$work/corpus/" || exit 1
count() { find "$1" -maxdepth 1 -type f | wc -l; }
echo "run.sh: $name for $seconds s from $(count "$work/corpus") seeds" \
     "($seeds, copied to $work/corpus)"

# libFuzzer's own exit code for a finding is 77 unless told otherwise,
# which ctest would take for "skipped": 1 for every kind. One input may
# take 10 s (the harnesses take milliseconds); 4096 bytes at most, as in
# the runs the README reports.
st=0
"$harness" -max_total_time="$seconds" -max_len=4096 -timeout=10 \
    -error_exitcode=1 -timeout_exitcode=1 -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" "$work/corpus" || st=$?

found=0
for f in "$work/artifacts"/crash-* "$work/artifacts"/leak-* \
    "$work/artifacts"/timeout-* "$work/artifacts"/oom-*; do
    [ -e "$f" ] || continue
    found=$((found + 1))
    kept=$findings/$name-${f##*/}
    cp "$f" "$kept"
    echo "run.sh: FINDING of $name: $kept ($(wc -c <"$f") bytes), in hex:"
    od -An -tx1 -v "$f"
    echo "run.sh: reproduce it:  $harness $kept"
    echo "run.sh: keep it as a regression input (fuzz_replay runs it in" \
         "every build once it is fixed):"
    echo "  cp '$kept' '$regressions/'"
done
if [ "$found" -gt 0 ]; then
    echo "run.sh: $name: $found finding(s), kept in $findings"
    exit 1
fi
if [ "$st" != 0 ]; then
    echo "run.sh: $name: libFuzzer ended with status $st and no finding"
    exit 1
fi
echo "run.sh: $name: nothing found in $seconds s; corpus now" \
     "$(count "$work/corpus") inputs"
exit 0
