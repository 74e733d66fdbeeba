#!/usr/bin/env python3
"""The Wireshark dissector against what was really sent.

run.py WSGEMU WSG_LUA SCHEMA_DUMP WORKDIR [CONTROL_CHECK]

Starts the emulator with --capture and talks to it as a driver would: over
TCP every command the schema has (schema_dump lists them, so rows added
to include/wsg/schema.h are covered with no change here), an auto-update
stream, a packet split over two writes, two packets in one write, a packet
with a bad checksum and a script command ID (B0h); over UDP a few
requests; on its serial line (--pty) one; and on a second emulator with --text-interface on a GCL session,
captured from the control channel's "capture start FILE" to its "capture
stop".
Every packet sent and received is kept as bytes, in order. Then Debian's
tshark decodes the captures with the generated wsg.lua (-T pdml, two
passes) and every packet it found is compared with the bytes of the same
place in the same direction: the ID, the size, the status, the checksum's
verdict, and each field of the request or reply by its name, decoded here
from the schema's layouts independently of the dissector; replies to a
request link to it. GCL lines compare as lines (kind, command, the ERR
code). Exits 77 where tshark is missing (scripts/deps.sh --test installs
tshark).
"""

import json
import os
import select
import shutil
import signal
import socket
import struct
import termios
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

SCALE = float(os.environ.get("WSG_TEST_TIME_SCALE", "1") or 1)
FAILS = []
COMPARED = [0]


def fail(msg):
    FAILS.append(msg)
    print("FAIL: " + msg)


# ---- the protocol, from the schema ---------------------------------------

def crc16(data, table):
    crc = 0xFFFF
    for b in data:
        crc = table[(crc ^ b) & 0xFF] ^ (crc >> 8)
    return crc


SIZES = {"u8": 1, "u16": 2, "u32": 4, "f32": 4, "i16_tenths": 2,
         "version": 2, "enum8": 1, "bits8": 1, "bits16": 2, "bits32": 4}


def key(s):
    return "".join(c if c.isalnum() else "_" for c in s.lower())


def fits(layout, n):
    fixed = sum(SIZES.get(f["type"], 0) for f in layout)
    if layout and layout[-1]["type"] in ("text", "bytes"):
        return fixed <= n <= fixed + layout[-1]["max"]
    return n == fixed


def decode(layout, data):
    """The fields of data as (name, type, value)."""
    out, off = [], 0
    for f in layout:
        t = f["type"]
        if t in ("text", "bytes"):
            v = data[off:]
            off = len(data)
        else:
            n = SIZES[t]
            raw = data[off:off + n]
            off += n
            if t == "f32":
                v = struct.unpack("<f", raw)[0]
            elif t == "i16_tenths":
                v = struct.unpack("<h", raw)[0] / 10.0
            else:
                v = int.from_bytes(raw, "little")
        out.append((f["name"], t, v))
    return out


def encode_value(f):
    t = f["type"]
    if t == "f32":
        return struct.pack("<f", 40.0)
    if t == "i16_tenths":
        return struct.pack("<h", 215)
    if t in ("bits8", "bits16", "bits32"):
        return bytes(SIZES[t])  # no flags: no stream, no reset
    if t == "u16":
        return struct.pack("<H", 0)
    if t in ("u8", "enum8"):
        return b"\x01"
    if t in ("u32", "version"):
        return (7).to_bytes(SIZES[t], "little")
    if t == "text":
        return b"ack"[:f["max"]]  # also AckFastStop's key
    return b"\x01\x02\x03"[:f["max"]]


def frame(cid, payload, table, bad=False):
    head = b"\xaa\xaa\xaa" + bytes([cid]) + struct.pack("<H", len(payload))
    head += payload
    crc = crc16(head, table)
    if bad:
        crc ^= 0x5A5A
    return head + struct.pack("<H", crc)


class Frames:
    """Frames out of a byte stream (or datagrams), in order."""

    def __init__(self):
        self.buf = b""
        self.frames = []

    def feed(self, data):
        self.buf += data
        while True:
            i = self.buf.find(b"\xaa\xaa\xaa")
            if i < 0 or len(self.buf) - i < 6:
                return
            self.buf = self.buf[i:]
            size = struct.unpack("<H", self.buf[4:6])[0]
            if len(self.buf) < size + 8:
                return
            self.frames.append(self.buf[:size + 8])
            self.buf = self.buf[size + 8:]


def recv_until(sock, frames, pred, limit=10.0):
    end = time.monotonic() + limit * SCALE
    while True:
        for i, f in enumerate(frames.frames):
            if i >= frames.seen and pred(f):
                frames.seen = i + 1
                return f
        left = end - time.monotonic()
        if left <= 0:
            return None
        r, _, _ = select.select([sock], [], [], left)
        if r:
            data = sock.recv(65536)
            if not data:
                return None
            frames.feed(data)


# ---- the emulator --------------------------------------------------------

def start(wsgemu, args):
    p = subprocess.Popen([wsgemu] + args, stdout=subprocess.PIPE,
                         stderr=sys.stderr, text=True)
    r, _, _ = select.select([p.stdout], [], [], 10 * SCALE)
    line = p.stdout.readline() if r else ""
    if not line.startswith("ready "):
        p.kill()
        raise SystemExit("FAIL: no ready line from %s (%r)" % (wsgemu, line))
    fields = dict(kv.split("=", 1) for kv in line.split()[1:])
    return p, fields


def stop(p):
    p.send_signal(signal.SIGTERM)
    try:
        rc = p.wait(10 * SCALE)
    except subprocess.TimeoutExpired:
        p.kill()
        rc = p.wait()
    if rc != 0:
        fail("wsgemu exited with status %d" % rc)


def port_of(addr):
    return int(addr.split(">")[0].rsplit(":", 1)[1])


# ---- the session ---------------------------------------------------------

def binary_session(schema, table, tcp_port, udp_port, pty_path):
    """Returns (sent, received) per link: {"tcp": ([...], [...]), ...}."""
    s = socket.create_connection(("127.0.0.1", tcp_port), 10 * SCALE)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    rx = Frames()
    rx.seen = 0
    sent = []
    bad = set()

    def send(pkt, split=None):
        if split:
            s.sendall(pkt[:split])
            time.sleep(0.2)  # a write apart, whatever the timing
            s.sendall(pkt[split:])
        else:
            s.sendall(pkt)
        sent.append(pkt)

    def final(cid):
        # Through E_CMD_PENDING to the final result of cid.
        f = recv_until(s, rx, lambda f: f[3] == cid and
                       struct.unpack("<H", f[6:8])[0] != 26, 30)
        if f is None:
            fail("no final answer to %02Xh" % cid)

    cmds = sorted((c for c in schema["commands"]), key=lambda c: c["id"])
    ids = [c["id"] for c in cmds]
    for c in cmds:
        if c["symbol"] == "DISCONNECT":
            continue
        payload = b"".join(encode_value(f) for f in c["request"])
        if not fits(c["request"], len(payload)) or not (
                c["min_len"] <= len(payload) <= c["max_len"]):
            payload = b""
        send(frame(c["id"], payload, table))
        final(c["id"])
    # An auto-update stream of the opening width: three values, then off.
    width = 0x43 if 0x43 in ids else None
    if width is not None:
        send(frame(width, b"\x01" + struct.pack("<H", 10), table))
        for _ in range(4):
            recv_until(s, rx, lambda f: f[3] == width)
        send(frame(width, b"\x00" + struct.pack("<H", 0), table))
    probe = 0x50 if 0x50 in ids else ids[0]
    send(frame(probe, b"", table))
    final(probe)
    # A packet split over two writes; two packets in one write.
    send(frame(probe, b"", table), split=4)
    final(probe)
    two = frame(probe, b"", table) * 2
    s.sendall(two)
    sent.append(two[:len(two) // 2])
    sent.append(two[len(two) // 2:])
    final(probe)
    final(probe)
    # A bad checksum: E_CHECKSUM_ERROR.
    bad.add(len(sent))
    send(frame(probe, b"", table, bad=True))
    final(probe)
    # A script's own ID, with no script: E_CMD_UNKNOWN.
    send(frame(0xB0, b"\x01\x02", table))
    final(0xB0)
    disc = [c["id"] for c in cmds if c["symbol"] == "DISCONNECT"]
    if disc:
        send(frame(disc[0], b"", table))
        final(disc[0])
    s.close()

    u = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    u.bind(("127.0.0.1", 0))
    urx = Frames()
    urx.seen = 0
    usent = []
    for cid in (probe, width or probe):
        pkt = frame(cid, b"", table)
        u.sendto(pkt, ("127.0.0.1", udp_port))
        usent.append(pkt)
        r, _, _ = select.select([u], [], [], 10 * SCALE)
        if r:
            urx.feed(u.recv(65536))
        else:
            fail("no UDP answer to %02Xh" % cid)
    u.close()

    # The serial line: its records carry their direction in the flags.
    fd = os.open(pty_path, os.O_RDWR | os.O_NOCTTY)
    attrs = termios.tcgetattr(fd)
    attrs[0] = attrs[1] = attrs[3] = 0  # raw: no input, output, local modes
    attrs[2] = termios.CS8 | termios.CREAD | termios.CLOCAL
    termios.tcsetattr(fd, termios.TCSANOW, attrs)
    prx = Frames()
    psent = [frame(width or probe, b"", table)]
    os.write(fd, psent[0])
    end = time.monotonic() + 10 * SCALE
    while not prx.frames and time.monotonic() < end:
        r, _, _ = select.select([fd], [], [], end - time.monotonic())
        if r:
            prx.feed(os.read(fd, 4096))
    os.close(fd)
    if not prx.frames:
        fail("no answer on the pty")
    return {"tcp": (sent, rx.frames, bad), "udp": (usent, urx.frames, set()),
            "pty": (psent, prx.frames, set())}


def gcl_session(port):
    s = socket.create_connection(("127.0.0.1", port), 10 * SCALE)
    s.settimeout(10 * SCALE)
    sent, got = [], []
    buf = b""
    for line, answers in (("VERBOSE=1", 1), ("HOME()", 2), ("POS?", 1),
                          ("FOO()", 1), ("BYE()", 1)):
        s.sendall(line.encode() + b"\n")
        sent.append(line)
        while answers > 0:
            while b"\n" not in buf:
                data = s.recv(4096)
                if not data:
                    fail("GCL: closed before the answer to " + line)
                    return sent, got
                buf += data
            ln, buf = buf.split(b"\n", 1)
            got.append(ln.decode())
            answers -= 1
    s.close()
    return sent, got


# ---- tshark --------------------------------------------------------------

def tshark(cap, lua, tcp_port, udp_port):
    cmd = ["tshark", "-r", cap, "-2", "-T", "pdml",
           "-X", "lua_script:" + lua,
           "-o", "wsg.tcp_ports:%d" % tcp_port,
           "-o", "wsg.udp_ports:%d" % udp_port]
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       text=True, timeout=120 * SCALE)
    err = "\n".join(ln for ln in r.stderr.splitlines()
                    if "dangerous" not in ln)
    if r.returncode != 0 or "Lua" in err or "rror" in err:
        raise SystemExit("FAIL: tshark %s:\n%s" % (" ".join(cmd), err))
    return ET.fromstring(r.stdout)


def fields_of(proto):
    out = {}
    for f in proto.iter("field"):
        out.setdefault(f.get("name"), []).append(f)
    return out


def pdus(root):
    """Per link ("tcp" or "udp"), the WSG packets in order as dicts."""
    links = {"tcp": [], "udp": [], "pty": [], "reassembled": 0}
    for pkt in root.iter("packet"):
        protos = [p.get("name") for p in pkt.findall("proto")]
        if any(f.get("name") == "tcp.segment" for f in pkt.iter("field")):
            links["reassembled"] += 1
        link = ("udp" if "udp" in protos else
                "tcp" if "tcp" in protos else "pty")
        num, ip = None, {}
        for p in pkt.findall("proto"):
            if p.get("name") == "frame":
                for f in p.iter("field"):
                    if f.get("name") == "frame.number":
                        num = int(f.get("show"))
            if p.get("name") == "ip":
                for f in p.iter("field"):
                    if f.get("name") in ("ip.src", "ip.dst"):
                        ip[f.get("name")] = f.get("show")
            if p.get("name") != "wsg":
                continue
            links[link].append({"frame": num, "f": fields_of(p), "ip": ip})
    return links


def show(d, name):
    v = d["f"].get(name)
    return v[0].get("show") if v else None


def compare(schema, expected, got, link):
    by_id = {c["id"]: c for c in schema["commands"]}
    sent, received, bad = expected
    req = [d for d in got if show(d, "wsg.reply") not in ("1", "True")]
    rep = [d for d in got if show(d, "wsg.reply") in ("1", "True")]
    for what, want, have, is_reply in (("request", sent, req, False),
                                       ("reply", received, rep, True)):
        if len(want) != len(have):
            fail("%s: %d %ss sent, the dissector found %d" %
                 (link, len(want), what, len(have)))
        for i, (pkt, d) in enumerate(zip(want, have)):
            where = "%s %s %d (frame %s, %02Xh)" % (link, what, i,
                                                   d["frame"], pkt[3])
            cid, size = pkt[3], struct.unpack("<H", pkt[4:6])[0]
            if int(show(d, "wsg.id"), 0) != cid:
                fail("%s: ID %s" % (where, show(d, "wsg.id")))
                continue
            if int(show(d, "wsg.size")) != size:
                fail("%s: size %s, sent %d" % (where, show(d, "wsg.size"),
                                               size))
            ok = "0" if (not is_reply and i in bad) else "1"
            if show(d, "wsg.checksum.status") != ok:
                fail("%s: checksum status %s, want %s" %
                     (where, show(d, "wsg.checksum.status"), ok))
            if 0xB0 <= cid <= 0xBF and cid not in by_id and \
                    show(d, "wsg.script") not in ("1", "True"):
                fail("%s: not shown as a script command" % where)
            payload = pkt[6:-2]
            status = None
            if is_reply:
                status = struct.unpack("<H", payload[:2])[0]
                if int(show(d, "wsg.status")) != status:
                    fail("%s: status %s, sent %d" %
                         (where, show(d, "wsg.status"), status))
                payload = payload[2:]
            c = by_id.get(cid)
            if not c:
                continue
            layout = c["reply"] if is_reply else c["request"]
            if is_reply and status != 0:
                continue
            if not fits(layout, len(payload)) or not payload and not layout:
                continue
            if not payload and not is_reply:
                continue
            base = "wsg.%s.%s." % (key(c["symbol"]), "rep" if is_reply
                                   else "req")
            for name, t, v in decode(layout, payload):
                fl = d["f"].get(base + key(name))
                if not fl:
                    fail("%s: no field %s" % (where, base + key(name)))
                    continue
                f = fl[0]
                COMPARED[0] += 1
                if t in ("f32", "i16_tenths"):
                    g = float(f.get("show"))
                    if abs(g - v) > 1e-3 * max(1.0, abs(v)):
                        fail("%s: %s %s, sent %r" % (where, name, g, v))
                elif t == "text":
                    if f.get("show") != v.decode("latin-1"):
                        fail("%s: %s %r, sent %r" % (where, name,
                                                     f.get("show"), v))
                elif t == "bytes":
                    if (f.get("value") or "") != v.hex():
                        fail("%s: %s %s, sent %s" % (where, name,
                                                     f.get("value"), v.hex()))
                else:
                    g = int(f.get("show"), 0)
                    if g != v:
                        fail("%s: %s %d, sent %d" % (where, name, g, v))
                    if t in ("bits8", "bits16", "bits32"):
                        # Each named bit, as a field of its own.
                        for fd in layout:
                            if fd["name"] != name:
                                continue
                            for bit, bn in fd.get("names", {}).items():
                                b = d["f"].get(base + key(name) + "." +
                                               key(bn))
                                want_b = (v >> int(bit)) & 1
                                if b is None or int(b[0].get("show") in
                                                    ("1", "True")) != want_b:
                                    fail("%s: bit %s of %s" % (where, bn,
                                                               name))
    # Linking: every reply of a command that was asked links to a request.
    asked = {pkt[3] for pkt in sent}
    streamed = 0
    for d in rep:
        cid = int(show(d, "wsg.id"), 0)
        if show(d, "wsg.request_in") is None:
            if show(d, "wsg.stream") in ("1", "True"):
                streamed += 1
            elif cid in asked:
                fail("%s: reply in frame %s links to no request" %
                     (link, d["frame"]))
    return streamed


def main():
    if len(sys.argv) < 5:
        print(__doc__)
        return 2
    wsgemu, lua, dump, work = sys.argv[1:5]
    if not shutil.which("tshark"):
        print("SKIP: no tshark (scripts/deps.sh --test installs tshark)")
        return 77
    os.makedirs(work, exist_ok=True)
    schema = json.loads(subprocess.run([dump], stdout=subprocess.PIPE,
                                       check=True, text=True).stdout)
    for c in schema["commands"]:
        for f in c["request"] + c["reply"]:
            if isinstance(f.get("names"), list):
                f["names"] = {i: n for i, n in enumerate(f["names"]) if n}
    table = crc_table()
    cap = os.path.join(work, "binary.pcapng")
    # UDP bound to every address: the capture still shows the one each
    # datagram came to, 127.0.0.1, not 0.0.0.0.
    p, ready = start(wsgemu, ["--tcp", "127.0.0.1:0", "--udp",
                              "0.0.0.0:0:source", "--pty",
                              os.path.join(work, "tty"), "--capture", cap,
                              "--time-scale", "20"])
    try:
        links = binary_session(schema, table, port_of(ready["tcp"]),
                               port_of(ready["udp"]), ready["pty"])
    finally:
        stop(p)
    root = tshark(cap, lua, port_of(ready["tcp"]), port_of(ready["udp"]))
    got = pdus(root)
    streamed = 0
    for link in ("tcp", "udp", "pty"):
        streamed += compare(schema, links[link], got[link], link)
    if streamed < 2:
        fail("only %d stream packets shown as unsolicited" % streamed)
    for d in got["udp"]:
        if d["ip"] != {"ip.src": "127.0.0.1", "ip.dst": "127.0.0.1"}:
            fail("udp frame %s: addresses %s, want 127.0.0.1 both ways" %
                 (d["frame"], d["ip"]))
    if not got["reassembled"]:
        print("note: the emulator read the split packet in one piece")
    print("binary: %d requests, %d replies over TCP, %d over UDP, "
          "%d streamed" % (len(links["tcp"][0]), len(links["tcp"][1]),
                           len(links["udp"][0]) + len(links["udp"][1]),
                           streamed))

    cap2 = os.path.join(work, "gcl.pcapng")
    # This one captures from the control channel's command, not --capture.
    p, ready = start(wsgemu, ["--tcp", "127.0.0.1:0", "--text-interface",
                              "on", "--control", "127.0.0.1:0",
                              "--time-scale", "20"])
    try:
        ctl = socket.create_connection(("127.0.0.1", port_of(ready["control"])),
                                       10 * SCALE)
        ctl_file = ctl.makefile("rw")

        def control(line):
            ctl_file.write(line + "\n")
            ctl_file.flush()
            return ctl_file.readline().rstrip("\n")

        ans = control("capture start " + cap2)
        if ans != "ok capture " + cap2:
            fail("capture start: %r" % ans)
        sent, answered = gcl_session(port_of(ready["tcp"]))
        ans = control("capture")
        if not ans.startswith("ok capture %s records " % cap2):
            fail("capture: %r" % ans)
        ans = control("capture stop")
        if not ans.startswith("ok capture stopped "):
            fail("capture stop: %r" % ans)
        if control("capture") != "ok capture off":
            fail("capture after stop is not off")
        ctl.close()
    finally:
        stop(p)
    root = tshark(cap2, lua, port_of(ready["tcp"]), 1500)
    lines = [d for d in pdus(root)["tcp"] if show(d, "wsg.gcl.line")]
    req = [show(d, "wsg.gcl.line") for d in lines
           if show(d, "wsg.gcl.kind") in ("call", "query", "setting")]
    rep = [d for d in lines
           if show(d, "wsg.gcl.kind") not in ("call", "query", "setting")]
    if req != sent:
        fail("GCL requests %r, sent %r" % (req, sent))
    if [show(d, "wsg.gcl.line") for d in rep] != answered:
        fail("GCL replies %r, received %r" %
             ([show(d, "wsg.gcl.line") for d in rep], answered))
    for d in rep:
        line = show(d, "wsg.gcl.line")
        if line.startswith("ERR ") and \
                show(d, "wsg.gcl.error") != line.split()[2]:
            fail("GCL %r: error %s" % (line, show(d, "wsg.gcl.error")))
        if line[:3] in ("ACK", "FIN") and \
                show(d, "wsg.gcl.command") != line.split()[1]:
            fail("GCL %r: command %s" % (line, show(d, "wsg.gcl.command")))
    print("gcl: %d lines sent, %d received" % (len(sent), len(answered)))
    if FAILS:
        print("%d failures; the captures are in %s" % (len(FAILS), work))
        return 1
    print("ok: %d fields, each as sent" % COMPARED[0])
    return 0


def crc_table():
    """The checksum table: not the generated dissector's, which would prove
    nothing, but the Python client's, made on its own
    (python/wsgemu/client.py)."""
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "..", "python"))
    from wsgemu.client import _CRC_TABLE  # noqa: E402
    return _CRC_TABLE


if __name__ == "__main__":
    sys.exit(main())
