#!/bin/bash
# run.sh: the Kubernetes manifests (deploy/kubernetes/) run with podman's
# `kube play`, as a cluster would run them, and talked to through their
# published ports. It builds the container image as the container test
# does (scripts/container.sh into a scratch podman storage), then for
# wsgemu.yaml and wsgemu-fleet.yaml:
#   play   `podman kube play` of the manifest, adapted here and only here
#          for podman: the image is the one just built (imagePullPolicy
#          Never) and each container port gets a hostPort of the same
#          number, podman's way of publishing it (a cluster reaches the
#          ports through the Service, which podman 4.3 does not make);
#   talk   over the published ports: wsgctl homes the gripper and reads
#          its width over TCP and over UDP, the control channel answers
#          `state`, the web page `/state.json` (by the Service's name, in
#          the config's web-host); the readiness probe's own command,
#          run in the container, answers; in the fleet gripper 3 is
#          serial 4 on TCP 1003 and gripper 1 answers on UDP 1502;
#   check  the security context took effect: the emulator runs as uid
#          65534 with no capability and no_new_privs, its root is mounted
#          read-only, and it wrote its log and capture on the emptyDir;
#   down   `podman kube down`, after which the pod is gone.
# It all runs in a network namespace of its own (unshare --net): the CNI
# bridge, its firewall rules and the published ports live and die there,
# and the host's network is not touched. podman's network configuration
# goes to the scratch directory too (network_config_dir).
#
# podman 4.3 turns the livenessProbe into a health check it schedules with
# systemd timers; without systemd it says so on stderr and runs the pod
# anyway. It ignores the readinessProbe: the test runs its command.
#
# Usage: run.sh SOURCE_DIR STATIC_BUILD_DIR
# Environment: WSG_KUBE_REQUIRE=1 makes "cannot run here" a failure.
# Exit status: 0 passed, 1 failed, 77 podman cannot run here (skipped).
set -eu

ME=run.sh
[ $# -eq 2 ] || { echo "usage: $ME SOURCE_DIR STATIC_BUILD_DIR" >&2; exit 2; }
SRC=$(cd "$1" && pwd)
STATIC=$2
IMAGE=localhost/wsgemu:ctest
py=/usr/bin/python3

cannot_run() {
    echo "$ME: cannot run the Kubernetes test here: $*" >&2
    if [ "${WSG_KUBE_REQUIRE:-0}" = 1 ]; then
        echo "$ME: WSG_KUBE_REQUIRE=1: that is a failure" >&2
        exit 1
    fi
    exit 77
}
fail() {
    echo "$ME: FAIL: $*" >&2
    exit 1
}

if [ -z "${WSG_KUBE_NETNS:-}" ]; then
    # Rootful podman: the test's own network namespace, its CNI bridge
    # and nsenter need root.
    [ "$(id -u)" = 0 ] || cannot_run "needs root (rootful podman, a network namespace)"
    command -v podman >/dev/null 2>&1 ||
        cannot_run "podman is not installed (scripts/deps.sh --test installs podman)"
    # The pod's infra container is podman's pause image, which podman
    # builds locally around catatonit.
    command -v catatonit >/dev/null 2>&1 || [ -x /usr/libexec/podman/catatonit ] ||
        cannot_run "podman's pod needs catatonit (scripts/deps.sh --test installs catatonit)"
    for t in unshare nsenter ip readelf; do
        command -v $t >/dev/null 2>&1 || cannot_run "$t is missing (scripts/deps.sh --test)"
    done
    "$py" -c 'import yaml' 2>/dev/null ||
        cannot_run "$py has no module yaml (scripts/deps.sh --test installs python3-yaml)"
    unshare --net true 2>/dev/null ||
        cannot_run "no new network namespace may be made here (unshare --net)"
    export WSG_KUBE_NETNS=1
    exec unshare --net "$0" "$@"
fi

# ---- in the test's own network namespace ---------------------------------

ip link set lo up

T=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-kube.XXXXXX")
cat >"$T/storage.conf" <<EOF
[storage]
driver = "vfs"
graphroot = "$T/root"
runroot = "$T/run"
EOF
mkdir -p "$T/cni"
# Resource limits within the host's and runc where crun is refused: what
# the container test finds this machine's runtime needs
# (docs/container.md); kube play takes no --ulimit or --runtime.
hn=$(ulimit -Hn)
runtime=
if command -v runc >/dev/null 2>&1; then runtime='runtime = "runc"'; fi
# podman 4.3's kube play leaves out the pod's sysctls: what the manifests
# ask for (net.ipv4.ip_unprivileged_port_start=0, so that uid 65534 binds
# ports 80 and 1000) is given as podman's default for every container
# instead; it applies in the pod's network namespace, as the cluster's.
cat >"$T/containers.conf" <<EOF
[containers]
default_ulimits = ["nofile=$hn:$hn", "nproc=1024:1024"]
default_sysctls = ["net.ipv4.ip_unprivileged_port_start=0"]
[network]
network_config_dir = "$T/cni"
[engine]
tmp_dir = "$T/tmp"
$runtime
EOF
export CONTAINERS_STORAGE_CONF=$T/storage.conf CONTAINERS_CONF=$T/containers.conf

PLAYED=""
cleanup() {
    local st=$? m
    set +e
    if [ -n "$PLAYED" ]; then
        timeout 60 podman kube down "$PLAYED" >/dev/null 2>&1
    fi
    timeout 60 podman pod rm -f -a -t 0 >/dev/null 2>&1
    findmnt -rn -o TARGET | grep "^$T/" | sort -r | while read -r m; do
        umount -l "$m"
    done
    rm -rf "$T"
    exit "$st"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "$ME: podman $(podman --version | sed 's/^podman version //'), storage in $T"
timeout 300 "$SRC/scripts/container.sh" --build-dir "$STATIC" --tag "$IMAGE" ||
    fail "scripts/container.sh could not build the image"
WSGCTL=$STATIC/tools/wsgctl

# adapt MANIFEST OUT: the podman-only changes (image, pull policy,
# hostPorts); the manifest itself stays standard Kubernetes.
adapt() {
    "$py" - "$1" "$2" "$IMAGE" <<'EOF'
import sys, yaml
src, out, image = sys.argv[1:]
docs = [d for d in yaml.safe_load_all(open(src)) if d]
for d in docs:
    if d["kind"] == "Deployment":
        for c in d["spec"]["template"]["spec"]["containers"]:
            c["image"] = image
            c["imagePullPolicy"] = "Never"
            for p in c.get("ports", []):
                p["hostPort"] = p["containerPort"]
with open(out, "w") as f:
    yaml.safe_dump_all(docs, f)
EOF
}

# probe MANIFEST: the readinessProbe's command, one word a line.
probe_cmd() {
    "$py" - "$1" <<'EOF'
import sys, yaml
for d in yaml.safe_load_all(open(sys.argv[1])):
    if d and d["kind"] == "Deployment":
        c = d["spec"]["template"]["spec"]["containers"][0]
        print("\n".join(c["readinessProbe"]["exec"]["command"]))
EOF
}

# play MANIFEST: kube play it, wait for the emulator's ready line; sets
# CTR (the emulator's container), PID (its pid on the host), READY.
play() {
    local m=$1 name i
    name=$(basename "$m" .yaml)
    adapt "$m" "$T/$name.yaml"
    PLAYED=$T/$name.yaml
    timeout 120 podman kube play "$PLAYED" >"$T/$name.play" 2>&1 || {
        cat "$T/$name.play" >&2
        fail "podman kube play $name.yaml"
    }
    CTR=$(podman ps -a --format '{{.Names}}' | grep -- "-wsgemu\$" | head -1)
    [ -n "$CTR" ] || fail "$name: no emulator container"
    for ((i = 0; i < 200; i++)); do
        podman logs "$CTR" >"$T/$name.out" 2>&1 || true
        grep -q '^ready ' "$T/$name.out" && break
        [ "$(podman inspect --format '{{.State.Running}}' "$CTR")" = true ] || break
        sleep 0.1
    done
    READY=$(grep -m1 '^ready ' "$T/$name.out") || {
        cat "$T/$name.out" >&2
        fail "$name: the emulator did not start"
    }
    PID=$(podman inspect --format '{{.State.Pid}}' "$CTR")
    echo "  $CTR: $READY"
}

down() {
    timeout 120 podman kube down "$PLAYED" >/dev/null 2>&1 ||
        fail "podman kube down $(basename "$PLAYED")"
    PLAYED=""
    [ -z "$(podman ps -a -q)" ] || fail "containers are left after kube down"
    echo "  down: no container left"
}

# The published ports are on the namespace's side of the CNI bridge: its
# address (a hostPort is forwarded from every local address but loopback).
gateway() {
    ip -4 -o addr show | awk '$2 ~ /^cni-podman/ { sub("/.*", "", $4); print $4; exit }'
}

# check_security: what the security context must have made of the
# emulator's process.
check_security() {
    local st uid caps nnp root
    st=/proc/$PID/status
    uid=$(awk '/^Uid:/ { print $2 "," $3 "," $4 "," $5 }' "$st")
    [ "$uid" = 65534,65534,65534,65534 ] || fail "the emulator's uids: $uid"
    caps=$(awk '/^Cap(Eff|Prm|Bnd|Amb):/ { printf "%s=%s ", $1, $2 }' "$st")
    [ "$(awk '/^Cap(Eff|Prm|Bnd|Amb):/ { print $2 }' "$st" | sort -u)" = 0000000000000000 ] ||
        fail "the emulator has capabilities: $caps"
    nnp=$(awk '/^NoNewPrivs:/ { print $2 }' "$st")
    [ "$nnp" = 1 ] || fail "no_new_privs is not set (allowPrivilegeEscalation)"
    root=$(awk '$5 == "/" { print $6 }' "/proc/$PID/mountinfo" | tail -1)
    case ,$root, in
    *,ro,*) ;;
    *) fail "the root file system is mounted $root, not read-only" ;;
    esac
    [ "$(podman inspect --format '{{.HostConfig.ReadonlyRootfs}}' "$CTR")" = true ] ||
        fail "podman does not run it with a read-only root"
    # The sysctl that lets uid 65534 bind ports 80 and 1000.
    [ "$(nsenter --net="/proc/$PID/ns/net" cat /proc/sys/net/ipv4/ip_unprivileged_port_start)" = 0 ] ||
        fail "net.ipv4.ip_unprivileged_port_start is not 0 in the pod"
    echo "  security: uid 65534, no capabilities, no_new_privs, root $root"
}

# udp_width GW PORT LOCAL: Get Opening Width (43h) over UDP from one
# socket bound to LOCAL, as a driver sends it; prints the width.
udp_width() {
    PYTHONPATH=$SRC/python timeout 30 "$py" - "$@" <<'EOF'
import socket, struct, sys
from wsgemu.client import encode_frame, FrameParser
gw, port, local = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("0.0.0.0", local))
s.settimeout(10)
s.sendto(encode_frame(0x43, bytes(3)), (gw, port))
f = FrameParser().feed(s.recv(1024))[0]
assert f.cmd == 0x43 and f.payload[:2] == bytes(2), (f.cmd, f.payload)
print("%.2f" % struct.unpack("<f", f.payload[2:6])[0])
EOF
}

# talk GW: the conversation over the published ports of a single gripper.
talk() {
    local gw=$1 out
    timeout 30 "$WSGCTL" --tcp "$gw:1000" --timeout 10 home || fail "wsgctl home over TCP"
    out=$(timeout 30 "$WSGCTL" --tcp "$gw:1000" --timeout 10 width) || fail "wsgctl width over TCP"
    echo "  tcp:     $out"
    [ "$out" = "width 110.00 mm" ] || fail "after homing: $out"
    # UDP through a published port (and a Service) is NATed: the answer
    # to the sender's port 1501 comes back through the NAT only to a
    # socket that sent from port 1501, as a driver with one socket bound
    # there does (docs/kubernetes.md). wsgctl sends from another port.
    out=$(udp_width "$gw" 1500 1501) || fail "no answer over UDP"
    echo "  udp:     width $out mm"
    [ "$out" = "110.00" ] || fail "over UDP: $out"
    # shellcheck disable=SC2016 # expanded by the inner bash
    out=$(GW=$gw timeout 30 bash -c 'exec 5<>"/dev/tcp/$GW/2000" &&
        printf "state\n" >&5 && read -r -t 10 line <&5 && echo "$line"') ||
        fail "no answer from the control channel"
    echo "  control: ${out:0:60}..."
    case $out in
    'ok {"width":110.000,'*) ;;
    *) fail "control state: $out" ;;
    esac
    # The web page by the Service's name, which the config's web-host
    # lets it answer to.
    # shellcheck disable=SC2016
    out=$(GW=$gw timeout 30 bash -c 'exec 5<>"/dev/tcp/$GW/80" &&
        printf "GET /state.json HTTP/1.0\r\nHost: $HOSTNAME_SVC\r\n\r\n" >&5 &&
        timeout 10 cat <&5') || fail "no answer from the web page"
    echo "  web:     $(head -1 <<<"$out" | tr -d '\r') (Host: $HOSTNAME_SVC)"
    case $out in
    'HTTP/1.'?' 200 OK'*'{"width":110.000,'*) ;;
    *) fail "web page: ${out:0:200}" ;;
    esac
}

# ready MANIFEST: the readiness probe's command, in the container.
ready_probe() {
    local out
    mapfile -t P < <(probe_cmd "$1")
    out=$(timeout 30 podman exec "$CTR" "${P[@]}") ||
        fail "the readiness probe fails: ${P[*]}"
    echo "  ready:   ${P[*]}: $out"
}

# files: the log and the capture, on the emptyDir, from the host's side.
check_files() {
    local d=/proc/$PID/root/var/lib/wsgemu
    grep -q ' connected' "$d/wsgemu.log" || fail "no log on the emptyDir"
    [ -s "$d/wsgemu.pcapng" ] || fail "no capture on the emptyDir"
    echo "  files:   $(ls "$d" | tr '\n' ' ')on the emptyDir"
}

echo "$ME: podman kube play deploy/kubernetes/wsgemu.yaml"
play "$SRC/deploy/kubernetes/wsgemu.yaml"
case $READY in
"ready tcp=0.0.0.0:1000 udp=0.0.0.0:1500>1501 control=0.0.0.0:2000 web=0.0.0.0:80") ;;
*) fail "wsgemu.yaml: $READY" ;;
esac
GW=$(gateway)
[ -n "$GW" ] || fail "no CNI bridge in the namespace"
echo "  published on $GW"
ready_probe "$SRC/deploy/kubernetes/wsgemu.yaml"
HOSTNAME_SVC=wsgemu talk "$GW"
check_security
# The capture is written through a buffer: a control command flushes it
# the way a batch of events does; stopping it closes the file.
exec 5<>"/dev/tcp/$GW/2000"
printf 'capture stop\n' >&5
read -r -t 10 line <&5 || fail "no answer to capture stop"
exec 5>&-
case $line in "ok capture stopped "*) ;; *) fail "capture stop: $line" ;; esac
check_files
down

echo "$ME: podman kube play deploy/kubernetes/wsgemu-fleet.yaml"
play "$SRC/deploy/kubernetes/wsgemu-fleet.yaml"
case $READY in
"ready tcp=0.0.0.0:1000,0.0.0.0:1001,0.0.0.0:1002,0.0.0.0:1003 udp=0.0.0.0:1500>1501,0.0.0.0:1502>1503,0.0.0.0:1504>1505,0.0.0.0:1506>1507 control=0.0.0.0:2000 web=0.0.0.0:80") ;;
*) fail "wsgemu-fleet.yaml: $READY" ;;
esac
GW=$(gateway)
ready_probe "$SRC/deploy/kubernetes/wsgemu-fleet.yaml"
HOSTNAME_SVC=wsgemu-fleet talk "$GW"
out=$(timeout 30 "$WSGCTL" --tcp "$GW:1003" --timeout 10 info) || fail "fleet: gripper 3"
grep -qx 'serial 4' <<<"$out" || fail "fleet: gripper 3 said: $out"
echo "  gripper 3 (tcp 1003): serial 4"
out=$(udp_width "$GW" 1502 1503) || fail "fleet: gripper 1 over UDP"
[ "$out" = "55.00" ] || fail "fleet: gripper 1 over UDP: $out"
echo "  gripper 1 (udp 1502): width $out mm"
check_security
down

echo "$ME: passed"
