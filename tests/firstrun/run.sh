#!/bin/bash
# run.sh: the README followed on a fresh Debian 12 by a new user, so that a
# missing install step fails here rather than for that user. It builds a
# fresh Debian 12 root with debootstrap (--variant=minbase, from the mirror
# this machine's apt uses, plus sudo), makes an ordinary user in it with
# sudo rights (as the installer makes a desktop's first user; sudo does not
# ask for the password, which nobody is there to type), clones this tree's
# HEAD into that user's home (git clone: what is committed, nothing else),
# and runs as that user, from the clone, every block of README.md and
# python/README.md that has the marker
#
#     <!-- firstrun -->              a shell block, run with bash -e
#     <!-- firstrun: serves -->      a shell block that serves in the
#                                    foreground (the quick start): its
#                                    ready line is waited for, then Ctrl-C
#                                    (SIGINT to its process group) must
#                                    end it with status 0
#     <!-- firstrun: pipe CMD -->    the block is CMD's stdin (a Python
#                                    example: .venv/bin/python -)
#     <!-- firstrun: save FILE -->   the block is written to FILE (a test
#                                    file a later block runs)
#
# on the line before the block's fence, exactly as written, in the order
# they appear. A block fails on any command that fails (bash -e), and when
# its output lacks what it shows: each line of a block that is a comment
# with two spaces, "#  TEXT" at its start, is output the block must print,
# in that order, among its other lines ("..." in TEXT stands for anything;
# leading and trailing blanks do not count). A block must stop what it
# started: a process of it still running in the root when it ends fails
# it (and is killed). Between blocks nothing is reset: the user's shell
# history, so to say, is the README's order.
#
# The .debs apt and debootstrap download are kept in a download cache,
# WSG_FIRSTRUN_CACHE (default /var/cache/wsgemu-firstrun), shared by runs
# (one at a time, by a lock); every run still builds a fresh root and
# installs into it. /proc, /sys and /dev are mounted into the root while it
# runs and always unmounted (a trap), and the root is removed.
#
# Usage: run.sh SOURCE_DIR [WORK_DIR]
#   WORK_DIR (default a new directory in /var/tmp) holds the root and each
#   block's script and output (block-N.sh, block-N.log), kept on failure.
# Environment: WSG_FIRSTRUN_CACHE (above); WSG_FIRSTRUN_KEEP=1 keeps the
#   work directory after a pass too.
# Exit status: 0 passed, 1 failed, 77 skipped: not root, no debootstrap or
#   git, no Debian mirror in apt's sources, or the mirror cannot be reached.
set -u

ME=firstrun
[ $# -ge 1 ] && [ $# -le 2 ] || { echo "usage: run.sh SOURCE_DIR [WORK_DIR]" >&2; exit 2; }
SRC=$(cd "$1" && pwd) || exit 2
CACHE=${WSG_FIRSTRUN_CACHE:-/var/cache/wsgemu-firstrun}
SUITE=bookworm
USERNAME=wsguser

say() { echo "$ME: $*"; }
skip() { say "skipped: $*"; exit 77; }
die() { say "FAIL: $*"; exit 1; }

[ "$(id -u)" = 0 ] || skip "needs root (debootstrap, chroot, mounts)"
for t in debootstrap git chroot mount umount flock; do
    command -v "$t" >/dev/null 2>&1 ||
        skip "$t is missing (scripts/deps.sh --test installs debootstrap and git)"
done
git -C "$SRC" rev-parse --verify -q HEAD >/dev/null ||
    skip "$SRC is not a git work tree with a commit to clone"

# ---- the mirror: the one apt uses here for Debian's main suite ----
# One-line sources ("deb [opts] URI SUITE COMPONENTS") and deb822 ones
# (URIs:, Suites:), for suites named bookworm*: the main archive is the
# URI of "bookworm", the security archive the URI of "bookworm-security".
sources_entries() {
    local f
    for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
        [ -f "$f" ] || continue
        sed -n 's/\[[^]]*\]//; s/^[[:space:]]*deb[[:space:]]\+\([^[:space:]]\+\)[[:space:]]\+\([^[:space:]]\+\).*/\1 \2/p' "$f"
    done
    for f in /etc/apt/sources.list.d/*.sources; do
        [ -f "$f" ] || continue
        awk 'function flush() { if (types ~ /(^| )deb( |$)/ && enabled != "no")
                 { n = split(uris, u, " "); m = split(suites, s, " ");
                   for (i = 1; i <= n; i++) for (j = 1; j <= m; j++)
                       print u[i], s[j] }
                 types = uris = suites = ""; enabled = "" }
             /^[[:space:]]*$/ { flush(); next }
             /^[Tt]ypes:/ { sub(/^[^:]*:[[:space:]]*/, ""); types = $0 }
             /^URIs:/ { sub(/^[^:]*:[[:space:]]*/, ""); uris = $0 }
             /^Suites:/ { sub(/^[^:]*:[[:space:]]*/, ""); suites = $0 }
             /^Enabled:/ { sub(/^[^:]*:[[:space:]]*/, ""); enabled = tolower($0) }
             END { flush() }' "$f"
    done
}
MIRROR=$(sources_entries | awk -v s="$SUITE" '$2 == s { print $1; exit }')
SECURITY=$(sources_entries | awk -v s="$SUITE-security" '$2 == s { print $1; exit }')
MIRROR=${MIRROR%/}
SECURITY=${SECURITY%/}
[ -n "$MIRROR" ] || skip "no '$SUITE' entry in /etc/apt/sources.list{,.d}: no Debian mirror to build from"

# Reachable? The suite's Release file, within 20 s (HTTP(S) with curl or
# wget where there, else plain HTTP over bash's /dev/tcp).
probe() {
    local url=$1/dists/$SUITE/Release hostport host port path
    if command -v curl >/dev/null 2>&1; then
        curl -sfI --max-time 20 "$url" >/dev/null
    elif command -v wget >/dev/null 2>&1; then
        wget -q --spider --timeout=20 "$url"
    else
        case $url in http://*) ;; *) return 1 ;; esac
        hostport=${url#http://}
        path=/${hostport#*/}
        hostport=${hostport%%/*}
        host=${hostport%%:*}
        port=80
        [ "$hostport" = "$host" ] || port=${hostport#*:}
        timeout 20 bash -c 'exec 3<>"/dev/tcp/$0/$1" &&
            printf "HEAD %s HTTP/1.0\r\nHost: %s\r\n\r\n" "$2" "$0" >&3 &&
            head -n 1 <&3 | grep -q " 200 "' "$host" "$port" "$path"
    fi
}
probe "$MIRROR" || skip "the mirror $MIRROR cannot be reached from here"
say "mirror $MIRROR${SECURITY:+, security $SECURITY}; download cache $CACHE"

# ---- one run at a time on the cache ----
mkdir -p "$CACHE/debootstrap" "$CACHE/apt/partial" || die "cannot make $CACHE"
exec 9>"$CACHE/lock"
if ! flock -n 9; then
    say "waiting for another run's lock on $CACHE"
    flock 9
fi

# ---- the work directory, the mounts and their cleanup ----
# A run killed outright (ctest's limit, SIGKILL) cannot unmount: what it
# left mounted in a root of ours is unmounted first, before anything
# could remove a directory with the host's /dev bound inside it.
for stale in $(awk '$2 ~ "^/var/tmp/wsgemu-firstrun\\.[^/]*/root/" { print $2 }' /proc/self/mounts | sort -r); do
    umount -R "$stale" 2>/dev/null || umount -R -l "$stale" 2>/dev/null ||
        say "warning: cannot unmount $stale, left by an earlier run"
done
if [ $# -ge 2 ]; then
    WORK=$2
    rm -rf "$WORK" && mkdir -p "$WORK" || die "cannot make $WORK"
else
    WORK=$(mktemp -d /var/tmp/wsgemu-firstrun.XXXXXX) || die "no work directory"
fi
WORK=$(cd "$WORK" && pwd)
ROOT=$WORK/root
mounted=()
status=1

cleanup() {
    local i m
    # Whatever still runs in the root (a failed block's server) goes first,
    # or its mounts stay busy.
    kill_root_procs KILL
    for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do
        m=${mounted[i]}
        umount -R "$m" 2>/dev/null || umount -R -l "$m" 2>/dev/null ||
            say "warning: cannot unmount $m"
    done
    mounted=()
    if [ "$status" = 0 ] && [ "${WSG_FIRSTRUN_KEEP:-0}" != 1 ]; then
        # Nothing may be mounted below it any more: rm would reach the host.
        if ! grep -q " $ROOT/" /proc/self/mounts; then
            rm -rf "$WORK"
        fi
    elif [ -d "$WORK" ]; then
        say "kept $WORK (each block's script and output: block-N.sh, block-N.log)"
    fi
}
trap 'cleanup' EXIT
trap 'exit 130' INT TERM

# The processes whose root is the chroot, but for this script's own.
root_procs() {
    local p r
    for p in /proc/[0-9]*; do
        r=$(readlink "$p/root" 2>/dev/null) || continue
        [ "$r" = "$ROOT" ] && echo "${p#/proc/}"
    done
}
kill_root_procs() {
    local p
    [ -d "$ROOT" ] || return 0
    for p in $(root_procs); do
        kill "-$1" "$p" 2>/dev/null
    done
}
mount_into() { # mount_into TARGET MOUNT-ARGS...
    local t=$1
    shift
    mkdir -p "$t" && mount "$@" "$t" || die "mount $* $t"
    mounted+=("$t")
    # Bind mounts stay private to the root: unmounting them never reaches
    # the host's own.
    mount --make-rslave "$t" 2>/dev/null || true
}

t_start=$(date +%s)
elapsed() { echo "$(($(date +%s) - t_start)) s"; }

# ---- a fresh Debian 12 ----
say "debootstrap --variant=minbase $SUITE into $ROOT ($(elapsed))"
if ! debootstrap --variant=minbase --include=sudo \
    --cache-dir="$CACHE/debootstrap" "$SUITE" "$ROOT" "$MIRROR/" \
    >"$WORK/debootstrap.log" 2>&1; then
    tail -n 30 "$WORK/debootstrap.log"
    die "debootstrap failed ($WORK/debootstrap.log)"
fi

# apt's sources as an installed Debian 12 has them: the release, its
# updates and the security archive.
{
    echo "deb $MIRROR $SUITE main"
    echo "deb $MIRROR $SUITE-updates main"
    [ -z "$SECURITY" ] || echo "deb $SECURITY $SUITE-security main"
} >"$ROOT/etc/apt/sources.list"
cp /etc/resolv.conf "$ROOT/etc/resolv.conf" 2>/dev/null || true
# A proxy this machine's apt goes through, the root's apt goes through too.
apt-config dump 2>/dev/null | grep -i '^Acquire::https\?::Proxy ' \
    >"$ROOT/etc/apt/apt.conf.d/01proxy" || rm -f "$ROOT/etc/apt/apt.conf.d/01proxy"
# The host name is the kernel's (the root shares it): the installer puts
# it in /etc/hosts, and sudo looks it up.
host=$(uname -n)
echo "$host" >"$ROOT/etc/hostname"
printf '127.0.0.1\tlocalhost\n127.0.1.1\t%s\n::1\tlocalhost ip6-localhost ip6-loopback\n' \
    "$host" >"$ROOT/etc/hosts"
# No service starts inside the root when a package is installed: nothing
# would stop it, and its mounts would stay busy (what Debian's own chroots
# and container images do).
printf '#!/bin/sh\nexit 101\n' >"$ROOT/usr/sbin/policy-rc.d"
chmod 755 "$ROOT/usr/sbin/policy-rc.d"

mount_into "$ROOT/proc" -t proc proc
mount_into "$ROOT/sys" -t sysfs sysfs
mount_into "$ROOT/dev" --rbind /dev
# apt's downloads: the cache, bound where apt keeps them.
mount_into "$ROOT/var/cache/apt/archives" --bind "$CACHE/apt"

in_root() { chroot "$ROOT" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 "$@"; }
say "apt-get update in the root, as an installed system has its lists ($(elapsed))"
in_root apt-get update -q >"$WORK/apt-update.log" 2>&1 ||
    { cat "$WORK/apt-update.log"; die "apt-get update in the root failed"; }

# The user: a home, bash, the groups the installer gives a desktop's
# first user, and sudo without a password prompt.
in_root useradd -m -s /bin/bash -G sudo,dialout,plugdev "$USERNAME" ||
    die "useradd failed"
echo "$USERNAME ALL=(ALL) NOPASSWD: ALL" >"$ROOT/etc/sudoers.d/firstrun"
chmod 440 "$ROOT/etc/sudoers.d/firstrun"
HOME_IN=/home/$USERNAME
TREE_IN=$HOME_IN/wsgemu

# ---- the project: HEAD, as git clone gets it ----
rev=$(git -C "$SRC" rev-parse --short HEAD)
say "git clone of $SRC ($rev) into $TREE_IN"
git clone -q --no-local "$SRC" "$ROOT$TREE_IN" || die "git clone failed"
in_root chown -R "$USERNAME:$USERNAME" "$TREE_IN" || die "chown failed"
if [ -n "$(git -C "$SRC" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
    say "note: $SRC has uncommitted changes; the clone has HEAD only"
fi

# ---- the blocks ----
# extract DOC PREFIX: writes each marked block of DOC (in the clone) to
# $WORK/PREFIX-N.body with its marker's mode in $WORK/PREFIX-N.mode; prints
# the count.
extract() {
    awk -v out="$WORK/$2" '
        function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
        /^<!-- *firstrun(:.*)? *-->[ \t]*$/ {
            m = $0; sub(/^<!-- *firstrun:? */, "", m); sub(/ *-->[ \t]*$/, "", m)
            pending = 1; mode = m; next }
        pending && /^```/ && !inblock {
            n++; inblock = 1; pending = 0
            print trim(mode) > (out "-" n ".mode"); close(out "-" n ".mode")
            printf "" > (out "-" n ".body"); next }
        inblock && /^```[ \t]*$/ { inblock = 0; close(out "-" n ".body"); next }
        inblock { print > (out "-" n ".body"); next }
        pending && /^[ \t]*$/ { next }
        pending { print "firstrun: marker not followed by a block: " $0 > "/dev/stderr"; pending = 0; bad = 1 }
        END { if (inblock) { print "firstrun: unclosed block" > "/dev/stderr"; bad = 1 }
              print n + 0; exit bad }' "$ROOT$TREE_IN/$1"
}

# The lines a block shows as its output: "#  TEXT" at the start of a line.
expected_lines() { sed -n 's/^#  \(.*\)$/\1/p' "$1"; }

# check_output BODY LOG: each expected line matches a line of LOG (both
# trimmed; "..." in the expected line matches anything), in order.
check_output() {
    local want got pat ok=0 line
    local -a log
    mapfile -t log <"$2"
    local i=0
    while IFS= read -r want; do
        want=$(printf '%s' "$want" | sed 's/^[[:space:]]*//; s/[[:space:]]*$//')
        [ -n "$want" ] || continue
        # A glob of it: the glob's own characters escaped, "..." a star.
        pat=$(printf '%s' "$want" | sed 's/[][*?\\]/\\&/g; s/\.\.\./*/g')
        got=0
        while [ $i -lt ${#log[@]} ]; do
            line=$(printf '%s' "${log[i]}" | sed 's/^[[:space:]]*//; s/[[:space:]]*$//')
            i=$((i + 1))
            # shellcheck disable=SC2053
            if [[ $line == $pat ]]; then
                got=1
                break
            fi
        done
        if [ $got = 0 ]; then
            say "  the output lacks (in order): $want"
            ok=1
            break
        fi
    done < <(expected_lines "$1")
    return $ok
}

# as_user SCRIPT...: the command line that has bash run SCRIPT (a path
# inside the root) as the user, in a login-like environment, from the
# clone, with -e: a command that fails ends it.
as_user=(chroot "$ROOT" /usr/sbin/runuser -u "$USERNAME" -- /usr/bin/env -i
    HOME="$HOME_IN" USER="$USERNAME" LOGNAME="$USERNAME" SHELL=/bin/bash
    PATH=/usr/local/bin:/usr/bin:/bin LANG=C.UTF-8 TERM=dumb
    /bin/bash -c 'cd "$0" && exec /bin/bash -e "$1"' "$TREE_IN")

# How long a block may take (the quick start builds; deps.sh downloads),
# and all of them together: bounds on a hang, not expectations, well
# within ctest's limit (3000 s), so that the trap always gets to unmount.
BLOCK_S=${WSG_FIRSTRUN_BLOCK_S:-1200}
ALL_S=${WSG_FIRSTRUN_ALL_S:-2400}

failures=0
nblocks=0
run_block() { # run_block PREFIX N DOC
    local body=$WORK/$1-$2.body mode rc t0 pid i name script log budget
    mode=$(cat "$WORK/$1-$2.mode")
    budget=$((ALL_S - ($(date +%s) - t_start)))
    [ $budget -lt "$BLOCK_S" ] || budget=$BLOCK_S
    nblocks=$((nblocks + 1))
    name="$3 block $2${mode:+ ($mode)}"
    script=$WORK/block-$nblocks.sh
    log=$WORK/block-$nblocks.log
    mkdir -p "$ROOT/tmp/firstrun" && chmod 755 "$ROOT/tmp/firstrun"
    case $mode in
    "" | serves) cp "$body" "$script" ;;
    pipe\ *) printf '%s <<'"'"'FIRSTRUN_EOF'"'"'\n%s\nFIRSTRUN_EOF\n' \
        "${mode#pipe }" "$(cat "$body")" >"$script" ;;
    save\ *) printf 'cat >%q <<'"'"'FIRSTRUN_EOF'"'"'\n%s\nFIRSTRUN_EOF\n' \
        "${mode#save }" "$(cat "$body")" >"$script" ;;
    *) say "FAIL: $name: unknown marker mode '$mode'"; failures=$((failures + 1)); return ;;
    esac
    cp "$script" "$ROOT/tmp/firstrun/block-$nblocks.sh"
    chmod 644 "$ROOT/tmp/firstrun/block-$nblocks.sh"
    say "--- $name ($(elapsed) so far):"
    sed 's/^/    /' "$body"
    t0=$(date +%s)
    rc=0
    if [ "$mode" = serves ]; then
        # In the background in a session of its own (the terminal's
        # foreground process group, as it were): ready, then Ctrl-C.
        setsid "${as_user[@]}" "/tmp/firstrun/block-$nblocks.sh" \
            >"$log" 2>&1 </dev/null &
        pid=$!
        i=0
        while ! grep -q '^ready ' "$log" && kill -0 "$pid" 2>/dev/null &&
            [ $i -lt $((budget * 10)) ]; do
            sleep 0.1
            i=$((i + 1))
        done
        if grep -q '^ready ' "$log"; then
            kill -INT -- "-$pid" 2>/dev/null
            i=0
            while kill -0 "$pid" 2>/dev/null && [ $i -lt 300 ]; do
                sleep 0.1
                i=$((i + 1))
            done
            kill -0 "$pid" 2>/dev/null && { kill -KILL -- "-$pid"; echo "(still running 30 s after Ctrl-C)" >>"$log"; }
        else
            kill -KILL -- "-$pid" 2>/dev/null
            echo "(no ready line)" >>"$log"
        fi
        wait "$pid"
        rc=$?
    else
        timeout -s KILL "$((budget > 1 ? budget : 1))" "${as_user[@]}" \
            "/tmp/firstrun/block-$nblocks.sh" >"$log" 2>&1 </dev/null
        rc=$?
    fi
    sed 's/^/  | /' "$log" | tail -n 200
    local bad=""
    [ "$rc" = 0 ] || bad="exit status $rc"
    if ! grep -q '^ready ' "$log" && [ "$mode" = serves ]; then
        bad="no ready line"
    fi
    if [ -z "$bad" ] && ! check_output "$body" "$log"; then
        bad="its output is not what the README shows"
    fi
    # Nothing of it may still run: the next block, or the user, would
    # find its ports taken.
    # A process the block signalled last (kill $!) may still be on its way
    # out: a bound of 10 s on that, not an expectation.
    local left i=0
    while [ -n "$(root_procs)" ] && [ $i -lt 100 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    left=$(for p in $(root_procs); do tr '\0' ' ' <"/proc/$p/cmdline" 2>/dev/null; echo; done | grep -v '^$')
    if [ -n "$left" ]; then
        [ -n "$bad" ] || bad="it left running: $(echo "$left" | tr '\n' ';')"
        kill_root_procs TERM
        sleep 1
        kill_root_procs KILL
    fi
    if [ -n "$bad" ]; then
        say "FAIL: $name: $bad ($(($(date +%s) - t0)) s)"
        failures=$((failures + 1))
    else
        say "ok: $name ($(($(date +%s) - t0)) s)"
    fi
}

for doc in README.md python/README.md; do
    prefix=$(echo "$doc" | tr '/.' '__')
    n=$(extract "$doc" "$prefix") || die "$doc: a marker without its block"
    say "$doc: $n marked blocks"
    for ((b = 1; b <= n; b++)); do
        run_block "$prefix" "$b" "$doc"
    done
done

[ $nblocks -gt 0 ] || die "no marked block in README.md or python/README.md"
echo "$ME: $((nblocks - failures)) passed, $failures failed ($(elapsed) in all)"
[ $failures = 0 ] && status=0
exit $status
