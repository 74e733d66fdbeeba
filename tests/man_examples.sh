#!/bin/bash
# man_examples.sh WSGEMU WSGCTL MANPAGE: the first block of wsgctl(1)'s
# EXAMPLES runs as written against an emulator with its defaults (TCP
# 1000, UDP 1500 answering to 1501, which the examples assume): every
# "$ " command exits 0 and prints the lines the page shows under it (in
# order, among its others). The defaults are the real gripper's ports, so
# it runs in a network namespace of its own (unshare -n, loopback up),
# where nothing else holds them: root and ip are needed, else exit 77.
set -u
if [ "${1:-}" != --inside ]; then
    [ $# -eq 3 ] || { echo "usage: man_examples.sh WSGEMU WSGCTL MANPAGE" >&2; exit 2; }
    if [ "$(id -u)" != 0 ] || ! command -v ip >/dev/null 2>&1 ||
        ! unshare -n true 2>/dev/null; then
        echo "man_examples: skipped: needs root, ip and unshare -n (a network namespace)"
        exit 77
    fi
    exec unshare -n bash "$0" --inside "$@"
fi
shift
wsgemu=$(realpath "$1")
wsgctl=$(realpath "$2")
man=$3
ip link set lo up || exit 1
tmp=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-manex.XXXXXX") || exit 1
bin=$tmp/bin
mkdir -p "$bin" && ln -s "$wsgctl" "$bin/wsgctl" || exit 1
pid=""
trap '[ -z "$pid" ] || kill "$pid" 2>/dev/null; rm -rf "$tmp"' EXIT

# The block: from .SH EXAMPLES to the first .fi, roff's escapes undone.
awk '/^\.SH / { on = ($0 == ".SH EXAMPLES") } on && /^\.fi/ { exit }
     on && started { print } on && /^\.nf/ { started = 1 }' "$man" |
    sed 's/\\-/-/g; s/\\(aq/'"'"'/g; s/\\e/\\/g' >"$tmp/block"
[ -s "$tmp/block" ] || { echo "FAIL: no EXAMPLES block in $man"; exit 1; }

"$wsgemu" >"$tmp/ready" 2>&1 &
pid=$!
for i in $(seq 300); do
    grep -q '^ready ' "$tmp/ready" && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.1
done
grep '^ready ' "$tmp/ready" || { cat "$tmp/ready"; echo "FAIL: no ready line"; exit 1; }

status=0
# Each command with the lines under it; run, then compare.
run_one() { # COMMAND, expected lines in $tmp/want
    local rc
    PATH="$bin:$PATH" bash -c "$1" >"$tmp/got" 2>&1 </dev/null
    rc=$?
    echo "\$ $1  -> $rc"
    sed 's/^/  /' "$tmp/got"
    if [ $rc != 0 ]; then
        echo "FAIL: exit $rc: $1"
        status=1
    fi
    # Each expected line, in order, among the output's.
    awk 'FILENAME == ARGV[1] { want[++n] = $0; next } k < n && $0 == want[k + 1] { k++ }
         END { if (k < n) { print "FAIL: the output lacks: " want[k + 1]; exit 1 } }' \
        "$tmp/want" "$tmp/got" || status=1
}
cmd=""
: >"$tmp/want"
while IFS= read -r line; do
    case $line in
    '$ '*)
        [ -z "$cmd" ] || run_one "$cmd"
        cmd=${line#\$ }
        : >"$tmp/want"
        ;;
    *) printf '%s\n' "$line" >>"$tmp/want" ;;
    esac
done <"$tmp/block"
[ -z "$cmd" ] || run_one "$cmd"
exit $status
