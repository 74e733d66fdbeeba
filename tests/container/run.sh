#!/bin/bash
# run.sh: the container image, built and run as a user would. It builds the
# image with scripts/container.sh (static wsgemu and wsgctl, podman build
# of the Containerfile) into a scratch podman storage that it removes at
# the end, then runs the image's entrypoint in each way this machine
# allows and talks to it over all three ports the image exposes:
#   run     podman run, with the image's own CMD, in a network namespace of
#           its own (--network none: nothing is changed on the host's
#           network); then a fleet (--grippers 3) given as arguments.
#           Where the runtime refuses podman's default resource limits it
#           retries with limits within the host's (--ulimit), and with
#           runc where crun refuses (a cgroup v1/v2 hybrid); what it
#           refused is printed;
#   rootfs  the image's exported root filesystem, its ENTRYPOINT and CMD
#           as the image records them, run with chroot in a new network
#           namespace: the fallback for a machine whose runtime refuses to
#           start containers at all (docs/container.md).
# Talking to it: wsgctl from the image homes the gripper and reads the
# width over TCP and over UDP, the control channel answers `state`; then
# SIGTERM must end it with status 0.
#
# Usage: run.sh SOURCE_DIR STATIC_BUILD_DIR
# Environment:
#   WSG_CONTAINER_MODE     auto (default: run where the runtime allows it,
#                          and rootfs), run (podman run must work), rootfs
#   WSG_CONTAINER_REQUIRE=1  no podman here is a failure instead of 77
# Exit status: 0 passed, 1 failed, 77 podman or root missing (skipped).
set -eu

ME=run.sh
[ $# -eq 2 ] || { echo "usage: $ME SOURCE_DIR STATIC_BUILD_DIR" >&2; exit 2; }
SRC=$(cd "$1" && pwd)
STATIC=$2
MODE=${WSG_CONTAINER_MODE:-auto}
IMAGE=localhost/wsgemu:ctest
case $MODE in auto | run | rootfs) ;; *) echo "$ME: bad mode $MODE" >&2; exit 2 ;; esac

cannot_run() {
    echo "$ME: cannot run the container test here: $*" >&2
    if [ "${WSG_CONTAINER_REQUIRE:-0}" = 1 ]; then
        echo "$ME: WSG_CONTAINER_REQUIRE=1: that is a failure" >&2
        exit 1
    fi
    exit 77
}
# Rootful podman (no subordinate ids to set up) and chroot need root.
[ "$(id -u)" = 0 ] || cannot_run "needs root (rootful podman, chroot)"
command -v podman >/dev/null 2>&1 ||
    cannot_run "podman is not installed (scripts/deps.sh --test installs it)"
for t in nsenter unshare chroot ip readelf; do
    command -v $t >/dev/null 2>&1 || cannot_run "$t is missing (scripts/deps.sh --test)"
done

fail() {
    echo "$ME: FAIL: $*" >&2
    exit 1
}

# Everything podman keeps goes under one scratch directory: the image
# store (vfs: plain directories, no overlay mounts to need), its run
# state and its temporary files.
T=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-ctr.XXXXXX")
cat >"$T/storage.conf" <<EOF
[storage]
driver = "vfs"
graphroot = "$T/root"
runroot = "$T/run"
EOF
cat >"$T/containers.conf" <<EOF
[engine]
tmp_dir = "$T/tmp"
EOF
export CONTAINERS_STORAGE_CONF=$T/storage.conf CONTAINERS_CONF=$T/containers.conf

# Containers are named here and removed by name; the rootfs process by
# its pid. Then nothing of the scratch store may stay mounted.
CTRS=(wsgemu-ctest-cmd wsgemu-ctest-fleet)
PID=""
cleanup() {
    local st=$? m
    set +e
    for c in "${CTRS[@]}"; do
        timeout 30 podman rm -f -t 0 "$c" >/dev/null 2>&1
    done
    if [ -n "$PID" ] && kill -0 "$PID" 2>/dev/null; then
        kill -KILL "$PID"
        wait "$PID" 2>/dev/null
    fi
    findmnt -rn -o TARGET | grep "^$T/" | sort -r | while read -r m; do
        umount -l "$m"
    done
    rm -rf "$T"
    exit "$st"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "$ME: podman $(podman --version | sed 's/^podman version //'), storage in $T"
timeout 300 "$SRC/scripts/container.sh" --build-dir "$STATIC" --tag "$IMAGE" \
    --export "$T/rootfs" ||
    fail "scripts/container.sh could not build the image"

# The image as it is: two static programs, and the entrypoint and default
# arguments that `podman run` would use.
podman image inspect --format '{{.Config.Labels}}' "$IMAGE" |
    grep -q "org.opencontainers.image.version:" || fail "no version label"
mapfile -t ENTRY < <(podman image inspect \
    --format '{{range .Config.Entrypoint}}{{println .}}{{end}}' "$IMAGE" |
    sed '/^$/d')
mapfile -t CMD < <(podman image inspect \
    --format '{{range .Config.Cmd}}{{println .}}{{end}}' "$IMAGE" |
    sed '/^$/d')
[ "${#ENTRY[@]}" -ge 1 ] || fail "the image has no ENTRYPOINT"
echo "$ME: image entrypoint: ${ENTRY[*]} ${CMD[*]}"
# The documents give the default arguments as the image has them: the
# README and docs/container.md, each with every one of them, in order.
for doc in README.md docs/container.md; do
    tr '\n' ' ' <"$SRC/$doc" | tr -s ' ' | grep -qF -- "${CMD[*]}" ||
        fail "$doc does not give the image's default arguments: ${CMD[*]}"
done
for f in wsgemu wsgctl; do
    [ -x "$T/rootfs/usr/bin/$f" ] || fail "the image has no /usr/bin/$f"
    if readelf -lW "$T/rootfs/usr/bin/$f" | grep -q INTERP; then
        fail "/usr/bin/$f in the image is dynamically linked"
    fi
done

# Wait until FILE (the daemon's output) holds the ready line, the daemon
# PID still running; print the line.
wait_ready() {
    local file=$1 pid=$2 i line
    for ((i = 0; i < 200; i++)); do
        line=$(grep -m1 '^ready ' "$file" 2>/dev/null || true)
        if [ -n "$line" ]; then
            echo "$line"
            return 0
        fi
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    echo "$ME: no ready line; the daemon said:" >&2
    cat "$file" >&2
    return 1
}

# talk PID WSGCTL...: the conversation of the test with the daemon PID, in
# its network namespace (where the ports are the image's own), through
# WSGCTL (the image's wsgctl, run inside the container's world).
talk() {
    local pid=$1 out
    shift
    timeout 30 "$@" --tcp 127.0.0.1:1000 --timeout 10 home ||
        fail "wsgctl home over TCP"
    out=$(timeout 30 "$@" --tcp 127.0.0.1:1000 --timeout 10 width) ||
        fail "wsgctl width over TCP"
    echo "  tcp:     $out"
    [ "$out" = "width 110.00 mm" ] || fail "after homing: $out"
    # UDP answers go to the sender's address at port 1501 (the image's
    # CMD): wsgctl receives there.
    out=$(timeout 30 "$@" --udp 127.0.0.1:1500:1501 --timeout 10 width) ||
        fail "wsgctl width over UDP"
    echo "  udp:     $out"
    [ "$out" = "width 110.00 mm" ] || fail "over UDP: $out"
    # shellcheck disable=SC2016 # expanded by the inner bash
    out=$(timeout 30 nsenter --net="/proc/$pid/ns/net" bash -c '
        exec 5<>/dev/tcp/127.0.0.1/2000 && printf "state\n" >&5 &&
        read -r -t 10 line <&5 && echo "$line"') ||
        fail "no answer from the control channel"
    echo "  control: ${out:0:60}..."
    case $out in
    'ok {"width":110.000,'*) ;;
    *) fail "control state: $out" ;;
    esac
    # The web page on port 80: its state as JSON. It answers only to its
    # own names in Host (a loopback one here), a request without one
    # neither.
    [ "${WEB:-}" = 1 ] || return 0
    # shellcheck disable=SC2016 # expanded by the inner bash
    out=$(timeout 30 nsenter --net="/proc/$pid/ns/net" bash -c '
        exec 5<>/dev/tcp/127.0.0.1/80 &&
        printf "GET /state.json HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n" >&5 &&
        timeout 10 cat <&5') || fail "no answer from the web page"
    echo "  web:     $(head -1 <<<"$out" | tr -d '\r')"
    case $out in
    'HTTP/1.'?' 200 OK'*'{"width":110.000,'*) ;;
    *) fail "web page: ${out:0:200}" ;;
    esac
}

# ---- podman run ----------------------------------------------------------

# The ways to start a container here, tried in turn until one starts the
# image: podman's defaults first (what a user types), then resource limits
# within the host's (without CAP_SYS_RESOURCE no runtime can raise them to
# podman's defaults, nofile 1048576), then runc in place of crun. The
# daemon is one process: a small nproc is plenty.
run_opts=""
probe_run() {
    local hn runtime tries=() t err
    hn=$(ulimit -Hn)
    local lim="--ulimit nofile=$hn:$hn --ulimit nproc=1024:1024"
    runtime=$(podman info --format '{{.Host.OCIRuntime.Name}}' 2>/dev/null || true)
    tries=("" "$lim")
    if [ "$runtime" != runc ] && command -v runc >/dev/null 2>&1; then
        tries+=("--runtime runc" "--runtime runc $lim")
    fi
    for t in "${tries[@]}"; do
        # shellcheck disable=SC2086 # options split on purpose
        if err=$(timeout 60 podman run --rm --network none $t "$IMAGE" \
            --help 2>&1 >/dev/null); then
            run_opts=$t
            echo "$ME: podman run works here with: ${t:-the defaults} (default runtime: ${runtime:-unknown})"
            return 0
        fi
        echo "$ME: podman run refused with ${t:-the defaults}: $(tail -1 <<<"$err")"
    done
    return 1
}

# run_container NAME [ARGS...]: podman run -d, wait for the ready line;
# PID is the daemon's pid (on the host), for its network namespace.
run_container() {
    local name=$1 i
    shift
    # shellcheck disable=SC2086
    timeout 60 podman run -d --name "$name" --network none $run_opts \
        "$IMAGE" "$@" >/dev/null || fail "podman run $name"
    PID=$(podman inspect --format '{{.State.Pid}}' "$name")
    for ((i = 0; i < 200; i++)); do
        podman logs "$name" >"$T/$name.out" 2>&1 || true
        grep -q '^ready ' "$T/$name.out" && break
        [ "$(podman inspect --format '{{.State.Running}}' "$name")" = true ] || break
        sleep 0.1
    done
    READY=$(wait_ready "$T/$name.out" "$PID") || fail "$name did not start"
    echo "  $READY"
}

# stop_container NAME: podman stop (SIGTERM, SIGKILL only after 20 s),
# which must end the daemon with status 0.
stop_container() {
    local name=$1 code
    timeout 60 podman stop -t 20 "$name" >/dev/null || fail "podman stop $name"
    code=$(podman inspect --format '{{.State.ExitCode}}' "$name")
    echo "  stopped: exit status $code"
    [ "$code" = 0 ] || fail "$name ended with status $code on SIGTERM"
    podman rm "$name" >/dev/null
    PID=""
}

ran=""
if [ "$MODE" != rootfs ]; then
    if probe_run; then
        echo "$ME: podman run $IMAGE (the image's CMD)"
        run_container wsgemu-ctest-cmd
        case $READY in
        "ready tcp=0.0.0.0:1000 udp=0.0.0.0:1500>1501 control=0.0.0.0:2000 web=0.0.0.0:80") ;;
        *) fail "the image's CMD should serve its exposed ports: $READY" ;;
        esac
        WEB=1 talk "$PID" podman exec wsgemu-ctest-cmd /usr/bin/wsgctl
        stop_container wsgemu-ctest-cmd

        # Arguments replace the CMD: a fleet counts its ports up.
        echo "$ME: podman run $IMAGE --grippers 3 (arguments replace the CMD)"
        run_container wsgemu-ctest-fleet --grippers 3 --tcp 0.0.0.0:1000 \
            --control 0.0.0.0:2000
        case $READY in
        "ready tcp=0.0.0.0:1000,0.0.0.0:1001,0.0.0.0:1002 control=0.0.0.0:2000") ;;
        *) fail "fleet: $READY" ;;
        esac
        out=$(timeout 30 podman exec wsgemu-ctest-fleet /usr/bin/wsgctl \
            --tcp 127.0.0.1:1002 --timeout 10 info) || fail "fleet: gripper 2"
        # Gripper i has serial number 1 + i.
        grep -qx 'serial 3' <<<"$out" || fail "fleet: gripper 2 said: $out"
        echo "  gripper 2: $(grep '^serial ' <<<"$out")"
        stop_container wsgemu-ctest-fleet
        ran="$ran run"
    elif [ "$MODE" = run ]; then
        fail "podman run is refused here (WSG_CONTAINER_MODE=run)"
    else
        echo "$ME: podman run is refused here; the exported root filesystem stands in"
    fi
fi

# ---- the exported root filesystem ----------------------------------------

if [ "$MODE" != run ]; then
    echo "$ME: the exported root filesystem: chroot $T/rootfs ${ENTRY[*]} ${CMD[*]}"
    # A network namespace of its own (loopback up), as podman gives; chroot
    # execs the entrypoint, so PID is the daemon and gets the SIGTERM.
    unshare --net sh -c 'ip link set lo up && exec chroot "$@"' sh \
        "$T/rootfs" "${ENTRY[@]}" "${CMD[@]}" >"$T/rootfs.out" 2>&1 &
    PID=$!
    READY=$(wait_ready "$T/rootfs.out" "$PID") || fail "the entrypoint did not start"
    echo "  $READY"
    # The ready line of the default arguments, as the documents show it.
    for doc in README.md docs/container.md; do
        grep -qF -- "# $READY" "$SRC/$doc" ||
            fail "$doc does not show the default ready line: $READY"
    done
    WEB=1 talk "$PID" nsenter --net="/proc/$PID/ns/net" chroot "$T/rootfs" /usr/bin/wsgctl
    kill -TERM "$PID"
    st=0
    wait "$PID" || st=$?
    PID=""
    echo "  stopped: exit status $st"
    [ "$st" = 0 ] || fail "the entrypoint ended with status $st on SIGTERM"
    ran="$ran rootfs"
fi

echo "$ME: passed:$ran"
