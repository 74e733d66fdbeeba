#!/usr/bin/python3
"""check.py: the Kubernetes manifests (deploy/kubernetes/*.yaml) are valid
YAML and agree with the image and the programs in it.

For each manifest: a ConfigMap, a Deployment and a Service, and
  - every key of the ConfigMap's wsgemu.conf and every option of the
    container's args is an option of `wsgemu --help`; the probes run
    /usr/bin/wsgctl with options of `wsgctl --help`, on the control port;
  - the config works: wsgemu runs with it (its addresses moved to
    loopback port 0, its files to a scratch directory) and prints its
    ready line;
  - the ports the container declares are exactly those the config serves
    (a fleet's counted up as README "A fleet of grippers in one process"
    says), and the Service gives each under the same number, by name;
  - the config is mounted where --config reads it, and every file the
    emulator writes (log, capture) lies on a writable emptyDir;
  - the security context: non-root, read-only root, no privilege
    escalation, every capability dropped, and the sysctl that lets a
    non-root user bind the gripper's ports below 1024.

Usage: check.py SOURCE_DIR WSGEMU WSGCTL. Exit 0 passed, 1 failed.
"""

import os
import re
import select
import subprocess
import sys
import tempfile
import time

try:
    import yaml
except ImportError:
    print("check.py: skipped: no python3-yaml (scripts/deps.sh --test "
          "installs it)")
    sys.exit(77)

ME = "check.py"
failures = []


def fail(where, what):
    failures.append(f"{where}: {what}")


def long_options(program):
    out = subprocess.run([program, "--help"], capture_output=True, text=True,
                         timeout=30).stdout
    return set(re.findall(r"(?<![\w-])--([a-z][a-z0-9-]*)", out))


def parse_conf(text):
    conf = {}
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        key, sep, value = line.partition("=")
        if not sep:
            raise ValueError(f"not key = value: {line!r}")
        conf[key.strip()] = value.strip()
    return conf


def port_of(addr):
    """"ADDR:PORT[:REMOTE]" or "PORT": (port, remote or None)."""
    parts = addr.split(":")
    if len(parts) == 1:
        return int(parts[0]), None
    if len(parts) == 2:
        return int(parts[1]), None
    return int(parts[1]), parts[2]


def served_ports(conf):
    """The (port, protocol) set the emulator serves with this config."""
    n = int(conf.get("grippers", "1"))
    ports = set()
    if "tcp" in conf:
        p, _ = port_of(conf["tcp"])
        ports |= {(p + i, "TCP") for i in range(n)}
    if "udp" in conf:
        p, remote = port_of(conf["udp"])
        step = 1
        if remote not in (None, "source"):
            r = int(remote)
            # README: s is 1 when the two ranges stay apart, else 2 (the
            # emulator refuses ranges that would still overlap).
            if n > 1 and not (p + n - 1 < r or r + n - 1 < p):
                step = 2
        ports |= {(p + i * step, "UDP") for i in range(n)}
    for key in ("control", "web"):
        if key in conf:
            ports.add((port_of(conf[key])[0], "TCP"))
    return ports


def run_config(where, conf, wsgemu):
    """wsgemu runs with the config: addresses on loopback port 0, files in
    a scratch directory; it must print its ready line."""
    with tempfile.TemporaryDirectory(prefix="wsgemu-kubecheck.") as tmp:
        lines = []
        for key, value in conf.items():
            if key in ("tcp", "control", "web"):
                value = "127.0.0.1:0"
            elif key == "udp":
                _, remote = port_of(value)
                value = "127.0.0.1:0" + (f":{remote}" if remote else "")
            elif value.startswith("/") and key not in ("config",):
                value = os.path.join(tmp, os.path.basename(value))
            lines.append(f"{key} = {value}")
        path = os.path.join(tmp, "wsgemu.conf")
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")
        p = subprocess.Popen([wsgemu, "--config", path], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        try:
            ready, _, _ = select.select([p.stdout], [], [], 30)
            line = p.stdout.readline() if ready else ""
            if not line.startswith("ready "):
                p.kill()
                fail(where, f"wsgemu does not start with the config: "
                     f"{line!r} {p.stderr.read()[:500]!r}")
                return
            for key in ("log", "capture"):
                if key in conf:
                    deadline = time.monotonic() + 10
                    f = os.path.join(tmp, os.path.basename(conf[key]))
                    while not os.path.exists(f) and time.monotonic() < deadline:
                        time.sleep(0.05)
                    if not os.path.exists(f):
                        fail(where, f"the config's {key} file was not made")
        finally:
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=30)


def check_security(where, pod, ctr):
    psc = pod.get("securityContext", {})
    csc = ctr.get("securityContext", {})
    if not (psc.get("runAsNonRoot") or csc.get("runAsNonRoot")):
        fail(where, "runAsNonRoot is not set")
    uid = csc.get("runAsUser", psc.get("runAsUser"))
    # The image has no USER and no /etc/passwd: the uid must be numeric
    # and given, or runAsNonRoot refuses to start it.
    if not isinstance(uid, int) or uid == 0:
        fail(where, f"runAsUser must be a non-zero uid, is {uid!r}")
    if csc.get("readOnlyRootFilesystem") is not True:
        fail(where, "readOnlyRootFilesystem is not true")
    if csc.get("allowPrivilegeEscalation") is not False:
        fail(where, "allowPrivilegeEscalation is not false")
    if csc.get("capabilities", {}).get("drop") != ["ALL"]:
        fail(where, "capabilities do not drop ALL")
    if csc.get("capabilities", {}).get("add"):
        fail(where, "capabilities are added")
    sysctls = {s["name"]: str(s["value"]) for s in psc.get("sysctls", [])}
    if sysctls.get("net.ipv4.ip_unprivileged_port_start") != "0":
        fail(where, "no sysctl net.ipv4.ip_unprivileged_port_start=0: "
             "a non-root emulator cannot bind ports below 1024")


def check_manifest(path, emu_opts, ctl_opts, wsgemu):
    where = os.path.relpath(path)
    with open(path) as f:
        docs = [d for d in yaml.safe_load_all(f) if d]
    kinds = {d["kind"]: d for d in docs}
    for k in ("ConfigMap", "Deployment", "Service"):
        if k not in kinds:
            fail(where, f"no {k}")
            return
    cm, dep, svc = kinds["ConfigMap"], kinds["Deployment"], kinds["Service"]
    pod = dep["spec"]["template"]["spec"]
    labels = dep["spec"]["template"]["metadata"]["labels"]
    if dep["spec"]["selector"]["matchLabels"].items() - labels.items():
        fail(where, "the Deployment's selector does not match its pods")
    if svc["spec"]["selector"].items() - labels.items():
        fail(where, "the Service's selector does not match the pods")
    ctrs = [c for c in pod["containers"] if c["name"] == "wsgemu"]
    if len(ctrs) != 1:
        fail(where, "no container named wsgemu")
        return
    ctr = ctrs[0]

    # The config and the arguments name options that exist.
    conf = parse_conf(cm["data"]["wsgemu.conf"])
    for key in conf:
        if key not in emu_opts:
            fail(where, f"config key {key!r} is no option of wsgemu --help")
    args = ctr.get("args", [])
    for a in args:
        if a.startswith("--") and a[2:].split("=")[0] not in emu_opts:
            fail(where, f"argument {a} is no option of wsgemu --help")
    if "--config" not in args:
        fail(where, "the container is not given --config")
        return
    conf_path = args[args.index("--config") + 1]

    # Mounts: the config where --config reads it, the written files on an
    # emptyDir.
    vols = {v["name"]: v for v in pod.get("volumes", [])}
    mounts = ctr.get("volumeMounts", [])

    def volume_at(p):
        best = None
        for m in mounts:
            mp = m["mountPath"].rstrip("/") + "/"
            if p.startswith(mp) and (best is None or
                                     len(mp) > len(best["mountPath"])):
                best = m
        return best

    m = volume_at(conf_path)
    if not m or vols.get(m["name"], {}).get("configMap", {}).get("name") != \
            cm["metadata"]["name"] or \
            os.path.basename(conf_path) != "wsgemu.conf":
        fail(where, f"{conf_path} is not the ConfigMap's wsgemu.conf")
    for key in ("log", "capture", "script-dir"):
        if key in conf:
            m = volume_at(conf[key])
            if not m or "emptyDir" not in vols.get(m["name"], {}) or \
                    m.get("readOnly"):
                fail(where, f"the {key} {conf[key]} is not on a writable "
                     "emptyDir")

    # Ports: declared = served; the Service the same numbers, by name.
    declared = {(p["containerPort"], p.get("protocol", "TCP"))
                for p in ctr.get("ports", [])}
    served = served_ports(conf)
    if declared != served:
        fail(where, f"the container declares ports {sorted(declared)}, the "
             f"config serves {sorted(served)}")
    by_name = {p["name"]: p for p in ctr.get("ports", [])}
    in_svc = set()
    for sp in svc["spec"]["ports"]:
        cp = by_name.get(sp.get("targetPort"))
        if cp is None:
            fail(where, f"Service port {sp['name']}: targetPort "
                 f"{sp.get('targetPort')!r} names no container port")
            continue
        if sp["port"] != cp["containerPort"] or \
                sp.get("protocol", "TCP") != cp.get("protocol", "TCP"):
            fail(where, f"Service port {sp['name']} is not the container's")
        in_svc.add((sp["port"], sp.get("protocol", "TCP")))
    if in_svc != declared:
        fail(where, f"the Service lacks {sorted(declared - in_svc)}")

    # Probes: wsgctl from the image, on the control channel.
    control = conf.get("control")
    for probe in ("readinessProbe", "livenessProbe"):
        if probe not in ctr:
            if probe == "readinessProbe":
                fail(where, "no readinessProbe")
            continue
        cmd = ctr[probe].get("exec", {}).get("command", [])
        if not cmd or cmd[0] != "/usr/bin/wsgctl":
            fail(where, f"{probe} does not run /usr/bin/wsgctl: {cmd}")
            continue
        for a in cmd[1:]:
            if a.startswith("--") and a[2:] not in ctl_opts:
                fail(where, f"{probe}: {a} is no option of wsgctl --help")
        if "--control" in cmd and control and \
                port_of(cmd[cmd.index("--control") + 1])[0] != \
                port_of(control)[0]:
            fail(where, f"{probe} asks another port than the control "
                 "channel's")

    check_security(where, pod, ctr)
    run_config(where, conf, wsgemu)
    print(f"{ME}: {where}: {len(declared)} ports, "
          f"{conf.get('grippers', '1')} gripper(s)")


def main():
    if len(sys.argv) != 4:
        print(f"usage: {ME} SOURCE_DIR WSGEMU WSGCTL", file=sys.stderr)
        return 2
    src, wsgemu, wsgctl = (os.path.abspath(a) for a in sys.argv[1:])
    emu_opts, ctl_opts = long_options(wsgemu), long_options(wsgctl)
    if "grippers" not in emu_opts or "control" not in ctl_opts:
        print(f"{ME}: FAIL: cannot read the options of --help", file=sys.stderr)
        return 1
    d = os.path.join(src, "deploy", "kubernetes")
    files = sorted(os.path.join(d, f) for f in os.listdir(d)
                   if f.endswith(".yaml"))
    if not files:
        print(f"{ME}: FAIL: no manifests in {d}", file=sys.stderr)
        return 1
    os.chdir(src)
    for path in files:
        check_manifest(path, emu_opts, ctl_opts, wsgemu)
    for f in failures:
        print(f"{ME}: FAIL: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
