#!/bin/sh
# low_port.sh WSGEMU: what an ordinary user is told when the emulator's
# defaults (TCP on the real gripper's port 1000) cannot be bound: status 1
# and every way out, as the README's "Port 1000" gives them: a port from
# 1024 up, root, setcap on this very program (in libcap2-bin, undone by a
# rebuild), the container image, the package's service. Run as root, the
# emulator runs as nobody (setpriv, no capabilities) from a copy in a
# scratch directory (the build tree may be closed to nobody); as another
# user, as that user.
# Exit 77 where an ordinary user may bind port 1000 here (the kernel's
# ip_unprivileged_port_start), or where root cannot drop to nobody.
set -u
wsgemu=$1
start=$(cat /proc/sys/net/ipv4/ip_unprivileged_port_start 2>/dev/null || echo 1024)
if [ "$start" -le 1000 ]; then
    echo "low_port: skipped: ports from $start up are open to every user here"
    exit 77
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-lowport.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
chmod 755 "$tmp"
cp "$wsgemu" "$tmp/wsgemu" && chmod 755 "$tmp/wsgemu" || exit 1
as=""
if [ "$(id -u)" = 0 ]; then
    if ! command -v setpriv >/dev/null 2>&1 ||
        ! setpriv --reuid=65534 --regid=65534 --clear-groups \
            --inh-caps=-all true 2>/dev/null; then
        echo "low_port: skipped: cannot run a program as nobody here (setpriv)"
        exit 77
    fi
    as="setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=-all"
fi

status=0
# check WHAT: the last run's stderr has WHAT.
check() {
    if grep -qF -- "$1" "$tmp/err"; then
        echo "ok: says: $1"
    else
        echo "FAIL: does not say: $1"
        status=1
    fi
}
# No options: the defaults, TCP 127.0.0.1:1000 among them. It must not
# start (a bounded wait: it should exit at once).
$as timeout 20 "$tmp/wsgemu" </dev/null >"$tmp/out" 2>"$tmp/err"
rc=$?
echo "wsgemu (defaults) as $(${as:-env} id -un): exit $rc"
cat "$tmp/err"
if [ "$rc" != 1 ]; then
    echo "FAIL: exit $rc, not 1"
    status=1
fi
check "cannot listen on tcp 127.0.0.1:1000: Permission denied"
check "--tcp 127.0.0.1:PORT with a PORT from 1024 up"
check "as root (sudo)"
check "sudo setcap cap_net_bind_service=+ep $tmp/wsgemu"
check "libcap2-bin"
check "a rebuild drops the capability"
check "container image"
check "wsgemu service"
# The way out it names works: a port from 1024 up (0: a free one). Its
# ready line is waited for (a bound, not an expectation), then SIGTERM.
$as "$tmp/wsgemu" --tcp 127.0.0.1:0 </dev/null >"$tmp/out" 2>"$tmp/err" &
pid=$!
i=0
while ! grep -q '^ready tcp=127.0.0.1:' "$tmp/out" && [ $i -lt 300 ] &&
    kill -0 $pid 2>/dev/null; do
    sleep 0.1
    i=$((i + 1))
done
if grep -q '^ready tcp=127.0.0.1:' "$tmp/out"; then
    echo "ok: with --tcp 127.0.0.1:0: $(cat "$tmp/out")"
else
    echo "FAIL: no ready line with --tcp 127.0.0.1:0"
    cat "$tmp/err"
    status=1
fi
kill $pid 2>/dev/null
wait $pid
exit $status
