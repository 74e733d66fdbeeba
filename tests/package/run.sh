#!/bin/bash
# run.sh: test what users install, the way they install it:
#   1. `cmake --install BUILD --prefix SCRATCH`: every file is there (the
#      two programs, the man pages, the config file and its example, the
#      systemd units, the docs), the benchmark tools are not; the man pages
#      render without warnings (where man is installed); the installed
#      wsgemu serves and the installed wsgctl talks to it; the installed
#      config file starts it, and so does a copy with every example setting
#      of it uncommented (but `can`, which needs a SocketCAN interface,
#      and the MuJoCo scene's two, which the example's builtin refuses),
#      whose values the gripper then shows; a bad line in it is refused;
#      logrotate's snippet (run by logrotate, where installed, on a
#      scratch copy of /var/log) rotates wsgemu.service's log and every
#      wsgemu@NAME's, and signals (SIGHUP) each service whose log it
#      rotated, and no other; where the build has the MuJoCo plant, its
#      module is installed and the installed wsgemu loads it.
#   2. the .deb from cpack: its fields (name, version, architecture,
#      dependencies, conffiles), its changelog (this version) and its
#      files; lintian finds no error and no warning in it (where lintian
#      is installed; scripts/deps.sh --test installs it); dpkg installs it into a
#      scratch root with a database of its own, the installed wsgemu
#      serves with the installed config, wsgctl talks to it, and with
#      --physics mujoco from the package's module; dpkg purges
#      it without leaving a file behind.
#   3. `systemd-analyze verify` on the installed units (wsgemu.service
#      and the template wsgemu@.service), with the installed man pages
#      (Documentation=man:wsgemu(1)), and `systemd-analyze security
#      --offline=true` rates each exposed 2.0 or lower (skipped where it
#      has no --offline); where there is no systemd-analyze these are
#      skipped. The template's sandbox is the unit's; the .deb's units must
#      be the installed ones but for the /usr paths in ExecStart.
# Every emulator started here listens on free ports (port 0) only.
#
# Usage: run.sh CMAKE CPACK BUILD_DIR SOURCE_DIR VERSION
# Exit status: 0 passed, 1 a check failed, 2 usage, 77 no dpkg here
#   (skipped).
set -eu

ME=run.sh
[ $# = 5 ] || {
    echo "usage: $ME CMAKE CPACK BUILD_DIR SOURCE_DIR VERSION" >&2
    exit 2
}
CMAKE=$1
CPACK=$2
BUILD=$3
SRC=$4
VERSION=$5

for p in dpkg dpkg-deb; do
    if ! command -v "$p" >/dev/null 2>&1; then
        echo "$ME: no $p here (not a Debian system?): skipped"
        exit 77
    fi
done

S=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-package.XXXXXX")
EMU_PID=
# shellcheck disable=SC2317 # run by the EXIT trap
cleanup() {
    # Only the emulator this script started, by its PID.
    if [ -n "$EMU_PID" ]; then
        kill "$EMU_PID" 2>/dev/null || true
        wait "$EMU_PID" 2>/dev/null || true
    fi
    rm -rf "$S"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

check() { echo "--- $*"; }
fail() {
    echo "FAIL: $*" >&2
    exit 1
}
# show FILE: a command's output, for a failure's context.
show() { sed 's/^/    | /' "$1" >&2; }

# start_emu NAME EXE ARGS...: start an emulator, wait up to 10 s for its
# ready line; sets EMU_PID and READY. Its output is in $S/NAME.out/.err.
start_emu() {
    local name=$1 i=0
    shift
    READY=
    "$@" >"$S/$name.out" 2>"$S/$name.err" </dev/null &
    EMU_PID=$!
    while [ $i -lt 100 ]; do
        # A whole line: it is written with its newline and flushed.
        if [ "$(wc -l <"$S/$name.out")" -ge 1 ]; then
            READY=$(head -n 1 "$S/$name.out")
            case $READY in ready\ *) return 0 ;; esac
        fi
        if ! kill -0 "$EMU_PID" 2>/dev/null; then
            local st=0
            wait "$EMU_PID" || st=$?
            EMU_PID=
            show "$S/$name.err"
            fail "$name: '$*' ended with status $st before its ready line"
        fi
        sleep 0.1
        i=$((i + 1))
    done
    show "$S/$name.err"
    fail "$name: no ready line within 10 s from '$*' (stdout: '$READY')"
}

# stop_emu NAME: SIGTERM must end the emulator with status 0.
stop_emu() {
    local st=0
    kill -TERM "$EMU_PID"
    wait "$EMU_PID" || st=$?
    EMU_PID=
    if [ "$st" != 0 ]; then
        show "$S/$1.err"
        fail "$1: SIGTERM ended the emulator with status $st, not 0"
    fi
    echo "    stopped by SIGTERM, status 0"
}

# tcp_port: the TCP port of the ready line (one gripper).
tcp_port() {
    local p=${READY#*tcp=127.0.0.1:}
    p=${p%%[ ,]*}
    case $p in '' | *[!0-9]*) fail "no TCP port in the ready line '$READY'" ;; esac
    echo "$p"
}

# ctl WSGCTL PORT ARGS...: wsgctl against the emulator; its output in
# $S/ctl.out, failing unless it ends with status 0.
ctl() {
    local exe=$1 port=$2 st=0
    shift 2
    timeout 30 "$exe" --tcp "127.0.0.1:$port" --timeout 10 "$@" \
        >"$S/ctl.out" 2>&1 || st=$?
    if [ "$st" != 0 ]; then
        show "$S/ctl.out"
        fail "wsgctl $* ended with status $st"
    fi
}

# talk WSGCTL PORT: info, home, width: a fresh gripper, homed, opens to its
# full stroke (110 mm for the default WSG 50).
talk() {
    check "wsgctl info: a WSG 50 with firmware (swrev) 2.2.0"
    ctl "$1" "$2" info
    grep -q '^swrev 2\.2\.0$' "$S/ctl.out" ||
        { show "$S/ctl.out"; fail "wsgctl info does not show swrev 2.2.0"; }
    check "wsgctl home: E_SUCCESS"
    ctl "$1" "$2" home
    check "wsgctl -q width after homing: 110.00"
    ctl "$1" "$2" -q width
    [ "$(cat "$S/ctl.out")" = 110.00 ] ||
        { show "$S/ctl.out"; fail "width after homing is not 110.00"; }
}

# version EXE NAME: --version prints exactly `NAME VERSION`.
version() {
    local exe=$1 name=$2 st=0 out
    check "$name --version prints '$name $VERSION'"
    out=$("$exe" --version 2>&1) || st=$?
    [ "$st" = 0 ] || fail "$name --version ended with status $st: $out"
    [ "$out" = "$name $VERSION" ] ||
        fail "$name --version printed '$out', not '$name $VERSION'"
}

# physics ROOT WSGEMU WSGCTL: where the build has the MuJoCo plant, its
# module is installed below ROOT (LIBDIR/wsgemu/plants/mujoco.so), and that wsgemu finds
# it there for --physics mujoco and serves.
physics() {
    local root=$1 emu=$2 ctlexe=$3 found
    if [ ! -f "$BUILD/plants/mujoco.so" ]; then
        check "this build has no MuJoCo plant: --physics mujoco not run (skipped)"
        return 0
    fi
    check "the MuJoCo plant's module is installed, and $emu loads it"
    found=$(cd "$root" && find . -path '*/lib/*wsgemu/plants/mujoco.so')
    [ -n "$found" ] || fail "no lib/.../wsgemu/plants/mujoco.so below $root"
    start_emu physics "$emu" --physics mujoco --tcp 127.0.0.1:0
    echo "    $found; $READY"
    grep -q "${found#.}" "/proc/$EMU_PID/maps" ||
        fail "$emu --physics mujoco runs without the installed module"
    talk "$ctlexe" "$(tcp_port)"
    stop_emu physics
}

# has_files ROOT PATH...: each PATH is a file below ROOT.
has_files() {
    local root=$1 missing=""
    shift
    for f in "$@"; do
        [ -f "$root/$f" ] || missing="$missing $f"
    done
    [ -z "$missing" ] || fail "missing below $root:$missing"
}

# ===================================================================
echo "=== 1. cmake --install into a scratch prefix"
P=$S/prefix
check "cmake --install $BUILD --prefix $P"
"$CMAKE" --install "$BUILD" --prefix "$P" >"$S/install.log" 2>&1 ||
    { show "$S/install.log"; fail "cmake --install failed"; }

DOC=share/doc/wsgemu
check "every file is installed"
has_files "$P" bin/wsgemu bin/wsgctl \
    etc/wsgemu/wsgemu.conf "$DOC/examples/wsgemu.conf" \
    etc/logrotate.d/wsgemu \
    lib/systemd/system/wsgemu.service lib/systemd/system/wsgemu@.service \
    "$DOC/LICENSE" "$DOC/copyright" "$DOC/README.md" "$DOC/changelog.gz"
for b in wsgemu wsgctl; do
    [ -x "$P/bin/$b" ] || fail "$P/bin/$b is not executable"
done
# Man pages: gzipped where the build had gzip, else as they are.
for m in wsgemu wsgctl; do
    if [ -f "$P/share/man/man1/$m.1.gz" ]; then
        gzip -dc "$P/share/man/man1/$m.1.gz" >"$S/$m.1"
    elif [ -f "$P/share/man/man1/$m.1" ]; then
        cp "$P/share/man/man1/$m.1" "$S/$m.1"
    else
        fail "no man page $P/share/man/man1/$m.1(.gz)"
    fi
    cmp -s "$S/$m.1" "$SRC/docs/man/$m.1" ||
        fail "the installed $m.1 differs from docs/man/$m.1"
done
check "the installed config, its example, LICENSE, README are the sources"
for pair in "etc/wsgemu/wsgemu.conf packaging/wsgemu.conf" \
    "etc/logrotate.d/wsgemu packaging/wsgemu.logrotate" \
    "$DOC/examples/wsgemu.conf packaging/wsgemu.conf" \
    "$DOC/LICENSE LICENSE" "$DOC/copyright LICENSE" \
    "$DOC/README.md README.md"; do
    # shellcheck disable=SC2086 # two words: installed path, source path
    set -- $pair
    cmp -s "$P/$1" "$SRC/$2" || fail "$P/$1 differs from $2"
done
# logrotate's snippet, run for real on a scratch copy of /var/log (its
# paths moved there) with a systemctl that only writes down what it is
# asked: the unit's log and each template instance's are rotated, and each
# emulator that writes one is told (SIGHUP), that one and no other.
check "logrotate's snippet: wsgemu.service's and each wsgemu@NAME's logs, each service signalled"
L=$S/logrotate
mkdir -p "$L/bin" "$L/log/wsgemu" "$L/log/wsgemu-cell4" \
    "$L/log/wsgemu-lab\x2d2"
for d in wsgemu wsgemu-cell4 'wsgemu-lab\x2d2'; do
    echo "a line" >"$L/log/$d/wsgemu.log"
done
sed "s|/var/log/|$L/log/|g" "$P/etc/logrotate.d/wsgemu" >"$L/wsgemu"
grep -q "^$L/log/wsgemu/\*\.log {" "$L/wsgemu" &&
    grep -q "^$L/log/wsgemu-\*/\*\.log {" "$L/wsgemu" ||
    { show "$L/wsgemu"; fail "the snippet lacks a stanza for /var/log/wsgemu/*.log or /var/log/wsgemu-*/*.log"; }
if command -v logrotate >/dev/null 2>&1; then
    printf '#!/bin/sh\necho "$*" >>"%s/calls"\n' "$L" >"$L/bin/systemctl"
    chmod 755 "$L/bin/systemctl"
    PATH="$L/bin:$PATH" logrotate -f -s "$L/state" "$L/wsgemu" \
        >"$L/out" 2>&1 || { show "$L/out"; fail "logrotate failed"; }
    for d in wsgemu wsgemu-cell4 'wsgemu-lab\x2d2'; do
        [ -f "$L/log/$d/wsgemu.log.1" ] && [ ! -e "$L/log/$d/wsgemu.log" ] ||
            { show "$L/out"; fail "$d/wsgemu.log was not rotated"; }
    done
    sort "$L/calls" >"$L/calls.sorted"
    printf '%s\n' 'kill --signal=HUP wsgemu.service' \
        'kill --signal=HUP wsgemu@cell4.service' \
        'kill --signal=HUP wsgemu@lab\x2d2.service' | sort >"$L/calls.want"
    cmp -s "$L/calls.sorted" "$L/calls.want" ||
        { show "$L/calls"; fail "logrotate signalled other than each rotated log's service once"; }
else
    echo "    no logrotate here (scripts/deps.sh --test installs it): its run is skipped"
fi

check "the benchmark tools are not installed"
for b in wsgbench wsgref; do
    [ ! -e "$P/bin/$b" ] || fail "$P/bin/$b is installed"
done
check "the units start this prefix's wsgemu with this prefix's config"
want="ExecStart=$P/bin/wsgemu --config $P/etc/wsgemu/wsgemu.conf"
grep -qxF "$want" "$P/lib/systemd/system/wsgemu.service" ||
    fail "no line '$want' in the installed unit"
want="ExecStart=$P/bin/wsgemu --config $P/etc/wsgemu/%i.conf"
grep -qxF "$want" "$P/lib/systemd/system/wsgemu@.service" ||
    fail "no line '$want' in the installed template unit"

if command -v man >/dev/null 2>&1; then
    for m in wsgemu wsgctl; do
        check "man page $m(1) renders without warnings"
        LC_ALL=C.UTF-8 MANWIDTH=80 man --warnings -l "$S/$m.1" \
            >"$S/man.out" 2>"$S/man.err" ||
            { show "$S/man.err"; fail "man -l $m.1 failed"; }
        [ ! -s "$S/man.err" ] || { show "$S/man.err"; fail "$m.1: warnings"; }
        grep -q "^NAME" "$S/man.out" || fail "$m.1 renders without NAME"
        grep -q "^ *$m - " "$S/man.out" || fail "$m.1: no '$m - ...' line"
    done
else
    check "no man here: the man pages are not rendered (skipped)"
fi

version "$P/bin/wsgemu" wsgemu
version "$P/bin/wsgctl" wsgctl

check "the installed wsgemu serves TCP on a free port"
start_emu plain "$P/bin/wsgemu" --tcp 127.0.0.1:0
echo "    $READY"
port=$(tcp_port)
talk "$P/bin/wsgctl" "$port"
stop_emu plain
physics "$P" "$P/bin/wsgemu" "$P/bin/wsgctl"

# The config file as installed; the command line overrides its ports.
check "wsgemu --config $P/etc/wsgemu/wsgemu.conf (free ports) starts"
start_emu conf "$P/bin/wsgemu" --config "$P/etc/wsgemu/wsgemu.conf" \
    --tcp 127.0.0.1:0 --udp 127.0.0.1:0:1501
echo "    $READY"
case $READY in
*udp=127.0.0.1:*'>1501'*) ;;
*) fail "the ready line has no UDP answering to 1501: '$READY'" ;;
esac
ctl "$P/bin/wsgctl" "$(tcp_port)" -q width
stop_emu conf

# Every setting the example shows, uncommented (lines "#key = value"),
# but the CAN interface; the file system's and the network's are
# overridden on the command line, and so is the pty's group (dialout
# needs root or a user in it). The values must show in the gripper.
check "the example config with every setting uncommented (but can, scene) starts"
# The example startup script is where the package puts it, here under P.
# scene and scene-fingers go with physics = mujoco and a scene file of the
# user's: the example's physics is builtin, which refuses them.
sed -e 's/^#\([a-z-]* = \)/\1/' -e '/^can = /d' \
    -e '/^scene = /d' -e '/^scene-fingers = /d' \
    -e "s|^script = /usr/|script = $P/|" \
    "$P/$DOC/examples/wsgemu.conf" >"$S/all.conf"
n=$(grep -c '^[a-z-]* = ' "$S/all.conf") || true
[ "$n" -ge 20 ] || fail "only $n settings in the uncommented example"
echo "    $n settings"
start_emu all "$P/bin/wsgemu" --config "$S/all.conf" \
    --tcp 127.0.0.1:0 --udp 127.0.0.1:0:1501 --pty "$S/tty" \
    --pty-group "$(id -g)" --control 127.0.0.1:0 --web 127.0.0.1:0 --log "$S/comm.log" \
    --capture "$S/capture.pcapng"
echo "    $READY"
case $READY in
*" pty=$S/tty"*" control=127.0.0.1:"*" web=127.0.0.1:"*) ;;
*) fail "the ready line lacks the pty, the control channel or the web page: '$READY'" ;;
esac
check "the example's tag and model hold: tag 'cell 4', WSG 50"
ctl "$P/bin/wsgctl" "$(tcp_port)" -q tag
[ "$(cat "$S/ctl.out")" = "cell 4" ] ||
    { show "$S/ctl.out"; fail "the tag is not 'cell 4' from the config"; }
ctl "$P/bin/wsgctl" "$(tcp_port)" info
grep -q 'WSG 50' "$S/ctl.out" || { show "$S/ctl.out"; fail "not a WSG 50"; }
check "the example startup script runs and answers B0h"
ctl "$P/bin/wsgctl" "$(tcp_port)" state
grep -q SF_SCRIPT_RUNNING "$S/ctl.out" ||
    { show "$S/ctl.out"; fail "40h does not show SF_SCRIPT_RUNNING"; }
ctl "$P/bin/wsgctl" "$(tcp_port)" raw 0xB0
grep -q "B0h.*E_SUCCESS" "$S/ctl.out" ||
    { show "$S/ctl.out"; fail "the script did not answer B0h"; }
stop_emu all
[ -s "$S/comm.log" ] || fail "the communication log is empty"

check "a bad line in the config file: status 2, naming file and line"
cp "$S/all.conf" "$S/bad.conf"
echo "accelerashun = 200" >>"$S/bad.conf"
line=$(wc -l <"$S/bad.conf")
st=0
"$P/bin/wsgemu" --config "$S/bad.conf" --tcp 127.0.0.1:0 \
    >"$S/bad.out" 2>&1 </dev/null || st=$?
[ "$st" = 2 ] || { show "$S/bad.out"; fail "status $st, not 2"; }
grep -qF "$S/bad.conf:$line" "$S/bad.out" ||
    { show "$S/bad.out"; fail "the message does not name $S/bad.conf:$line"; }

# ===================================================================
echo "=== 2. the Debian package"
check "cpack --config $BUILD/CPackConfig.cmake"
"$CPACK" --config "$BUILD/CPackConfig.cmake" -B "$S/deb" \
    >"$S/cpack.log" 2>&1 || { show "$S/cpack.log"; fail "cpack failed"; }
arch=$(dpkg --print-architecture)
DEB=$S/deb/wsgemu_${VERSION}_$arch.deb
[ -f "$DEB" ] || { ls -l "$S/deb" >&2; fail "no $DEB"; }
echo "    $(basename "$DEB")"

check "control fields: Package, Version, Architecture, Section, Maintainer"
field() { dpkg-deb -f "$DEB" "$1"; }
[ "$(field Package)" = wsgemu ] || fail "Package is '$(field Package)'"
[ "$(field Version)" = "$VERSION" ] || fail "Version is '$(field Version)'"
[ "$(field Architecture)" = "$arch" ] ||
    fail "Architecture is '$(field Architecture)', not $arch"
[ -n "$(field Section)" ] || fail "no Section"
[ -n "$(field Maintainer)" ] || fail "no Maintainer"
[ -n "$(field Description)" ] || fail "no Description"
deps=$(field Depends)
echo "    Depends: $deps"
# A dynamically linked program needs libc6 (a static one, -DWSG_STATIC=ON,
# needs nothing).
if ldd "$P/bin/wsgemu" >/dev/null 2>&1; then
    check "Depends names libc6, and this machine has what it names"
    case ", $deps" in *", libc6"*) ;; *) fail "Depends has no libc6: '$deps'" ;; esac
else
    check "static programs: this machine has what Depends names, if anything"
fi
# Each "name (op version)"; an alternative ("a | b") is not expected.
while read -r d; do
    [ -n "$d" ] || continue
    case $d in *'|'*) fail "unexpected alternative in Depends: $d" ;; esac
    name=${d%% *}
    have=$(dpkg-query -W -f='${Version}' "$name" 2>/dev/null) ||
        fail "Depends: $name is not installed here"
    case $d in
    *'('*)
        rel=${d#*(}
        rel=${rel%)}
        op=${rel%% *}
        ver=${rel#* }
        case $op in
        '>=') dop=ge ;; '<=') dop=le ;; '>>') dop=gt ;; '<<') dop=lt ;;
        '=') dop=eq ;; *) fail "Depends: unknown relation in '$d'" ;;
        esac
        dpkg --compare-versions "$have" "$dop" "$ver" ||
            fail "Depends: $d, but this machine has $name $have"
        ;;
    esac
done <<EOF
$(echo "$deps" | tr ',' '\n')
EOF
# The README says what the package depends on: each of Depends, in the
# form dpkg-deb shows it, in its Debian package section.
check "README.md's Debian package section names each of Depends"
awk '/^### / { on = ($0 == "### The Debian package") } on' "$SRC/README.md" |
    tr '\n' ' ' | tr -s ' ' >"$S/readme-deb"
while read -r d; do
    [ -n "$d" ] || continue
    grep -qF -- "\`$d\`" "$S/readme-deb" ||
        fail "README.md's Debian package section does not name \`$d\` (Depends: $deps)"
done <<EOF
$(echo "$deps" | tr ',' '\n' | sed 's/^ *//')
EOF
check "conffiles: /etc/wsgemu/wsgemu.conf, /etc/logrotate.d/wsgemu"
dpkg-deb -I "$DEB" conffiles >"$S/conffiles" 2>&1 ||
    { show "$S/conffiles"; fail "the package has no conffiles"; }
for f in /etc/wsgemu/wsgemu.conf /etc/logrotate.d/wsgemu; do
    grep -qx "$f" "$S/conffiles" ||
        { show "$S/conffiles"; fail "$f is no conffile"; }
done

check "the changelog: Debian's format, this version, gzip -9n"
dpkg-deb --fsys-tarfile "$DEB" |
    tar -xO ./usr/share/doc/wsgemu/changelog.gz >"$S/changelog.gz" ||
    fail "no /usr/share/doc/wsgemu/changelog.gz in the package"
gzip -dc "$S/changelog.gz" >"$S/changelog"
if command -v dpkg-parsechangelog >/dev/null 2>&1; then
    v=$(dpkg-parsechangelog -l "$S/changelog" -S Version)
    [ "$v" = "$VERSION" ] ||
        fail "the changelog's latest version is '$v', not $VERSION (packaging/changelog.in)"
fi

# lintian: no error, no warning. The one finding allowed is the
# maintainer placeholder of an unconfigured build (WSG_MAINTAINER in
# CMakeLists.txt), which lintian rightly calls bogus.
if command -v lintian >/dev/null 2>&1; then
    check "lintian: no errors, no warnings"
    suppress=
    case $(field Maintainer) in
    *'<unset@invalid>')
        echo "    Maintainer is the placeholder (set WSG_MAINTAINER): its two tags are suppressed"
        suppress="--suppress-tags bogus-mail-host,bogus-mail-host-in-debian-changelog"
        ;;
    esac
    st=0
    # shellcheck disable=SC2086 # none or two words
    lintian --fail-on error,warning $suppress "$DEB" >"$S/lintian.out" 2>&1 ||
        st=$?
    # Root gets a notice on stderr; findings are the lines "E: " and "W: ".
    if [ "$st" != 0 ] || grep -q '^[EW]: ' "$S/lintian.out"; then
        show "$S/lintian.out"
        fail "lintian: status $st, or errors or warnings"
    fi
else
    check "no lintian here (scripts/deps.sh --test installs it): not run (skipped)"
fi

check "the package's files"
dpkg-deb -c "$DEB" | awk '{ print $NF }' | sed 's|^\./|/|' >"$S/files"
missing=""
for f in /usr/bin/wsgemu /usr/bin/wsgctl \
    /usr/share/man/man1/wsgemu.1.gz /usr/share/man/man1/wsgctl.1.gz \
    /etc/wsgemu/wsgemu.conf /usr/share/doc/wsgemu/examples/wsgemu.conf \
    /etc/logrotate.d/wsgemu \
    /usr/lib/systemd/system/wsgemu.service \
    /usr/lib/systemd/system/wsgemu@.service /usr/share/doc/wsgemu/copyright \
    /usr/share/doc/wsgemu/LICENSE /usr/share/doc/wsgemu/README.md \
    /usr/share/doc/wsgemu/changelog.gz; do
    grep -qxF "$f" "$S/files" || missing="$missing $f"
done
[ -z "$missing" ] || { show "$S/files"; fail "not in the package:$missing"; }
if grep -q 'wsgbench\|wsgref' "$S/files"; then
    fail "the benchmark tools are in the package"
fi

# A root of its own with an empty dpkg database: nothing on this machine
# is touched. The database knows no libc6, hence --force-depends (the
# dependencies were checked against this machine above). dpkg wants
# ldconfig and start-stop-daemon on its PATH, which may lack the sbin
# directories when not root.
R=$S/root
mkdir -p "$R/var/lib/dpkg/info" "$R/var/lib/dpkg/updates"
: >"$R/var/lib/dpkg/status"
DPKG="dpkg --root=$R --log=/dev/null --force-not-root --force-depends"
export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"
check "dpkg -i into the scratch root $R"
# shellcheck disable=SC2086
$DPKG -i "$DEB" >"$S/dpkg.log" 2>&1 || { show "$S/dpkg.log"; fail "dpkg -i"; }
st=$(dpkg --root="$R" -s wsgemu 2>/dev/null | sed -n 's/^Status: //p')
[ "$st" = "install ok installed" ] || fail "dpkg says wsgemu is '$st'"
v=$(dpkg --root="$R" -s wsgemu | sed -n 's/^Version: //p')
[ "$v" = "$VERSION" ] || fail "dpkg says version '$v', not $VERSION"
has_files "$R" usr/bin/wsgemu usr/bin/wsgctl etc/wsgemu/wsgemu.conf \
    usr/lib/systemd/system/wsgemu.service usr/share/doc/wsgemu/copyright
check "the package's units: ExecStart with /usr/bin and /etc"
grep -qxF "ExecStart=/usr/bin/wsgemu --config /etc/wsgemu/wsgemu.conf" \
    "$R/usr/lib/systemd/system/wsgemu.service" ||
    fail "the package's unit has not the /usr paths in ExecStart"
grep -qxF "ExecStart=/usr/bin/wsgemu --config /etc/wsgemu/%i.conf" \
    "$R/usr/lib/systemd/system/wsgemu@.service" ||
    fail "the package's template unit has not the /usr paths in ExecStart"
for u in wsgemu.service wsgemu@.service; do
    cp "$R/usr/lib/systemd/system/$u" "$S/deb.$u"
done

version "$R/usr/bin/wsgemu" wsgemu
version "$R/usr/bin/wsgctl" wsgctl
check "the package's wsgemu serves with the package's config (free ports)"
start_emu deb "$R/usr/bin/wsgemu" --config "$R/etc/wsgemu/wsgemu.conf" \
    --tcp 127.0.0.1:0 --udp 127.0.0.1:0:1501
echo "    $READY"
talk "$R/usr/bin/wsgctl" "$(tcp_port)"
stop_emu deb
physics "$R" "$R/usr/bin/wsgemu" "$R/usr/bin/wsgctl"

check "dpkg --purge leaves no file of the package"
# shellcheck disable=SC2086
$DPKG --purge wsgemu >"$S/dpkg.log" 2>&1 ||
    { show "$S/dpkg.log"; fail "dpkg --purge"; }
left=$(cd "$R" && find . -path ./var/lib/dpkg -prune -o ! -type d -print)
[ -z "$left" ] || fail "left after the purge: $left"

# ===================================================================
echo "=== 3. the systemd units"
U=$P/lib/systemd/system
if command -v systemd-analyze >/dev/null 2>&1; then
    for u in wsgemu.service wsgemu@.service; do
        # The template is verified as its instance wsgemu@i.service.
        check "systemd-analyze verify $u (installed man pages for Documentation=)"
        st=0
        MANPATH=$P/share/man systemd-analyze verify "$U/$u" \
            >"$S/verify.out" 2>&1 || st=$?
        # It reports an unknown key or a bad value, but exits 0 for it.
        if [ "$st" != 0 ] || [ -s "$S/verify.out" ]; then
            show "$S/verify.out"
            fail "systemd-analyze verify $u: status $st, or it reported something"
        fi
    done
    # The sandbox: systemd's own rating of the exposure, 0.0 (none) to
    # 10.0, of the unit file as it is (--offline, systemd 250 and later).
    if systemd-analyze security --help 2>&1 | grep -q -- --offline; then
        for u in wsgemu.service wsgemu@.service; do
            check "systemd-analyze security --offline=true $u: exposure 2.0 or lower"
            st=0
            systemd-analyze security --offline=true "$U/$u" \
                >"$S/security.out" 2>&1 || st=$?
            level=$(sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p' \
                "$S/security.out")
            [ "$st" = 0 ] && [ -n "$level" ] ||
                { show "$S/security.out"; fail "systemd-analyze security $u: status $st, no level"; }
            echo "    exposure $level"
            awk -v l="$level" 'BEGIN { exit !(l <= 2.0) }' ||
                { show "$S/security.out"; fail "$u: exposure $level, above 2.0"; }
        done
    else
        check "systemd-analyze here has no --offline: the sandbox is not rated (skipped)"
    fi
else
    check "no systemd-analyze here: the units are not verified (skipped)"
fi
check "the template's sandbox is the unit's, line for line"
# Only the description, the config file and the directories named after
# the instance differ (and the leading comments).
for u in wsgemu.service wsgemu@.service; do
    sed -e '/^#/d' -e '/^Description=/d' -e '/^ExecStart=/d' \
        -e '/^[A-Za-z]*Directory=/d' "$U/$u" >"$S/sandbox.$u"
done
diff "$S/sandbox.wsgemu.service" "$S/sandbox.wsgemu@.service" >&2 ||
    fail "wsgemu@.service differs from wsgemu.service in more than its instance's names"
grep -qx 'StateDirectory=wsgemu-%i' "$U/wsgemu@.service" ||
    fail "the template has no state directory of the instance's own"
for u in wsgemu.service wsgemu@.service; do
    check "the package's $u is the installed one but for ExecStart's paths"
    grep -v '^ExecStart=' "$U/$u" >"$S/unit.prefix"
    grep -v '^ExecStart=' "$S/deb.$u" >"$S/unit.deb"
    diff "$S/unit.prefix" "$S/unit.deb" >&2 ||
        fail "the package's $u differs from the installed one"
done
echo "package: all checks passed"
