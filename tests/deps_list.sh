#!/bin/sh
# deps_list.sh SOURCE_DIR: every Debian package a test names as its need
# (the packages of need_python, and what "scripts/deps.sh --test installs
# ..." names in a skip message) is one that scripts/deps.sh --test
# installs, so that the README's test command sets up what its tests use
# on a fresh machine (python_wheel once failed there: Debian's pip was
# missing).
set -u
src=$1
tmp=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-depslist.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
sh "$src/scripts/deps.sh" --test --print | sort -u >"$tmp/have" ||
    { echo "FAIL: scripts/deps.sh --test --print"; exit 1; }
{
    # need_python WHO "PACKAGES" ...: the quoted list on its own line or not.
    grep -rhA1 '^need_python [a-z]' "$src/tests" |
        sed -n 's/.*"\([a-z0-9.+ -]*\)".*/\1/p'
    # "(scripts/deps.sh --test installs X Y)": the words that name packages.
    grep -rhoE 'deps\.sh --test installs [a-z0-9.+ -]+' "$src/tests" "$src/scripts" |
        sed 's/.*installs //'
} | tr ' ' '\n' | grep -E '^[a-z0-9][a-z0-9.+-]+$' |
    grep -vxE 'it|them|and|what|the|its' | sort -u >"$tmp/need"
[ -s "$tmp/need" ] || { echo "FAIL: found no package named by the tests"; exit 1; }
missing=$(comm -23 "$tmp/need" "$tmp/have")
if [ -n "$missing" ]; then
    echo "FAIL: named by the tests, not installed by scripts/deps.sh --test:" $missing
    exit 1
fi
echo "ok: the $(wc -l <"$tmp/need") packages the tests name are all in scripts/deps.sh --test:" $(cat "$tmp/need")
