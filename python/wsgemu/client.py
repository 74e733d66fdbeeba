"""Clients of a WSG gripper (or of wsgemu) and of wsgemu's control channel.

``Gripper`` speaks the WSG binary protocol of command set 2.2.0 over TCP or
UDP: every command by name with human units (mm, mm/s, mm/s², N, °C), a
motion's ``E_CMD_PENDING`` waited through for its final result, and any
other status raised as ``WsgError`` carrying the status name the manual
uses. Over TCP, ``close()`` sends the Disconnect Announcement (07h) first,
since a gripper whose TCP client closes without it goes into FAST STOP.

``Control`` speaks wsgemu's control channel: one line per command, one
``ok ...`` or ``error ...`` line per answer; it places parts and obstacles,
raises faults, pauses and steps simulated time, and runs, stops and reads
the Lua scripts on the gripper.

Standard library only, so it runs wherever Python 3.9 or later does.
"""

import enum
import json
import os
import socket
import struct
import time
from types import TracebackType
from typing import (Any, Dict, List, Literal, NamedTuple, Optional, Tuple,
                    Type, Union, overload)

__all__ = [
    "Cmd",
    "Control",
    "ControlError",
    "Frame",
    "FrameParser",
    "GraspState",
    "GraspStats",
    "Gripper",
    "Pending",
    "Reply",
    "Status",
    "SystemFlag",
    "SystemInfo",
    "SystemLimits",
    "WsgError",
    "WsgTimeout",
    "crc16",
    "encode_frame",
    "status_name",
]

PREAMBLE = b"\xaa\xaa\xaa"
#: Largest payload a frame can announce (its SIZE field is 16 bits).
PAYLOAD_MAX = 0xFFFF


class Status(enum.IntEnum):
    """Status codes of the manual's Appendix A."""

    E_SUCCESS = 0
    E_NOT_AVAILABLE = 1
    E_NO_SENSOR = 2
    E_NOT_INITIALIZED = 3
    E_ALREADY_RUNNING = 4
    E_FEATURE_NOT_SUPPORTED = 5
    E_INCONSISTENT_DATA = 6
    E_TIMEOUT = 7
    E_READ_ERROR = 8
    E_WRITE_ERROR = 9
    E_INSUFFICIENT_RESOURCES = 10
    E_CHECKSUM_ERROR = 11
    E_NO_PARAM_EXPECTED = 12
    E_NOT_ENOUGH_PARAMS = 13
    E_CMD_UNKNOWN = 14
    E_CMD_FORMAT_ERROR = 15
    E_ACCESS_DENIED = 16
    E_ALREADY_OPEN = 17
    E_CMD_FAILED = 18
    E_CMD_ABORTED = 19
    E_INVALID_HANDLE = 20
    E_NOT_FOUND = 21
    E_NOT_OPEN = 22
    E_IO_ERROR = 23
    E_INVALID_PARAMETER = 24
    E_INDEX_OUT_OF_BOUNDS = 25
    E_CMD_PENDING = 26
    E_OVERRUN = 27
    E_RANGE_ERROR = 28
    E_AXIS_BLOCKED = 29
    E_FILE_EXISTS = 30


def status_name(status: int) -> str:
    """"E_SUCCESS", ...; "E_UNKNOWN" outside Appendix A (as wsgemu logs)."""
    try:
        return Status(status).name
    except ValueError:
        return "E_UNKNOWN"


class Cmd(enum.IntEnum):
    """Command IDs of command set 2.2.0 (and 46h of later firmware)."""

    LOOP = 0x06
    DISCONNECT = 0x07
    HOMING = 0x20
    PREPOSITION = 0x21
    STOP = 0x22
    FAST_STOP = 0x23
    ACK_FAST_STOP = 0x24
    GRASP = 0x25
    RELEASE = 0x26
    SET_ACCELERATION = 0x30
    GET_ACCELERATION = 0x31
    SET_FORCE_LIMIT = 0x32
    GET_FORCE_LIMIT = 0x33
    SET_SOFT_LIMITS = 0x34
    GET_SOFT_LIMITS = 0x35
    CLEAR_SOFT_LIMITS = 0x36
    OVERDRIVE = 0x37
    TARE = 0x38
    GET_SYSTEM_STATE = 0x40
    GET_GRASP_STATE = 0x41
    GET_GRASP_STATS = 0x42
    GET_WIDTH = 0x43
    GET_SPEED = 0x44
    GET_FORCE = 0x45
    GET_TEMPERATURE = 0x46
    GET_SYSTEM_INFO = 0x50
    SET_DEVICE_TAG = 0x51
    GET_DEVICE_TAG = 0x52
    GET_SYSTEM_LIMITS = 0x53
    # The finger commands of later firmware (docs/fingers.md).
    GET_FINGER1_INFO = 0x60
    GET_FINGER1_FLAGS = 0x61
    FINGER1_POWER = 0x62
    GET_FINGER1_DATA = 0x63
    GET_FINGER2_INFO = 0x70
    GET_FINGER2_FLAGS = 0x71
    FINGER2_POWER = 0x72
    GET_FINGER2_DATA = 0x73


#: The commands answered E_CMD_PENDING first and their result later.
MOTION_COMMANDS = frozenset({Cmd.HOMING, Cmd.PREPOSITION, Cmd.GRASP,
                             Cmd.RELEASE})


def _cmd_label(cmd: int) -> str:
    try:
        return "%02Xh %s" % (cmd, Cmd(cmd).name)
    except ValueError:
        return "%02Xh" % cmd


class SystemFlag(enum.IntFlag):
    """Bits of the system state (40h), chapter 4 of the manual."""

    SF_REFERENCED = 1 << 0
    SF_MOVING = 1 << 1
    SF_BLOCKED_MINUS = 1 << 2
    SF_BLOCKED_PLUS = 1 << 3
    SF_SOFT_LIMIT_MINUS = 1 << 4
    SF_SOFT_LIMIT_PLUS = 1 << 5
    SF_AXIS_STOPPED = 1 << 6
    SF_TARGET_POS_REACHED = 1 << 7
    SF_OVERDRIVE_MODE = 1 << 8
    SF_FORCECNTL_MODE = 1 << 9
    SF_FAST_STOP = 1 << 12
    SF_TEMP_WARNING = 1 << 13
    SF_TEMP_FAULT = 1 << 14
    SF_POWER_FAULT = 1 << 15
    SF_CURR_FAULT = 1 << 16
    SF_FINGER_FAULT = 1 << 17
    SF_CMD_FAILURE = 1 << 18
    SF_SCRIPT_RUNNING = 1 << 19
    SF_SCRIPT_FAILURE = 1 << 20


class FingerFlag(enum.IntFlag):
    """Bits of Get Finger Flags (61h/71h), wsgemu's choice
    (docs/fingers.md)."""

    POWERED = 1 << 0
    DATA = 1 << 1
    FAULT = 1 << 2
    CONTACT = 1 << 3
    UART = 1 << 4
    SPI = 1 << 5
    OVERRUN = 1 << 6


class GraspState(enum.IntEnum):
    """Grasping states (41h) as real grippers report them."""

    IDLE = 0
    GRASPING = 1
    NO_PART = 2
    PART_LOST = 3
    HOLDING = 4
    RELEASING = 5
    POSITIONING = 6
    ERROR = 7


class GraspStats(NamedTuple):
    total: int
    no_part: int
    lost_part: int


class SystemInfo(NamedTuple):
    type: int
    type_name: str
    hardware_revision: int
    firmware: str
    serial_number: int


class SystemLimits(NamedTuple):
    stroke: float
    min_speed: float
    max_speed: float
    min_acceleration: float
    max_acceleration: float
    min_force: float
    nominal_force: float
    overdrive_force: float


_DEVICE_TYPES = {0: "unknown", 1: "WSG 50", 2: "WSG 32", 3: "KMS 40",
                 4: "WTS", 5: "WSG 25", 6: "WSG 70"}


class WsgError(Exception):
    """The gripper answered a command with a status other than E_SUCCESS."""

    def __init__(self, cmd: int, status: int, params: bytes = b""):
        self.cmd = cmd
        self.status = status
        self.status_name = status_name(status)
        self.params = params
        super().__init__("%s: %s" % (_cmd_label(cmd), self.status_name))


class WsgTimeout(TimeoutError):
    """No answer (or no final result) arrived in time."""


# ---- the frame codec ----

def _make_crc_table() -> List[int]:
    # CRC-CCITT, polynomial 0x1021, table built MSB-first (the manual's
    # Appendix C; its printed table is mangled, so it is generated here).
    table = []
    for i in range(256):
        c = i << 8
        for _ in range(8):
            c = ((c << 1) ^ 0x1021) if c & 0x8000 else (c << 1)
        table.append(c & 0xFFFF)
    return table


_CRC_TABLE = _make_crc_table()


def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """The WSG checksum of data: start 0xFFFF, updated byte by byte as
    crc = T[(crc ^ b) & 0xFF] ^ (crc >> 8), as the gripper computes it."""
    for b in data:
        crc = _CRC_TABLE[(crc ^ b) & 0xFF] ^ (crc >> 8)
    return crc


def encode_frame(cmd: int, payload: bytes = b"") -> bytes:
    """A whole packet: preamble, ID, SIZE (LE), payload, CRC (LE)."""
    if not 0 <= cmd <= 0xFF:
        raise ValueError("command ID %r is not a byte" % (cmd,))
    if len(payload) > PAYLOAD_MAX:
        raise ValueError("payload of %d bytes does not fit SIZE"
                         % len(payload))
    head = PREAMBLE + struct.pack("<BH", cmd, len(payload)) + bytes(payload)
    return head + struct.pack("<H", crc16(head))


class Frame(NamedTuple):
    cmd: int
    payload: bytes


class FrameParser:
    """Cuts a byte stream into frames. Packets with a wrong checksum are
    counted in ``bad_crc`` and skipped, and the parser looks for the next
    preamble after the bad packet's first byte, so garbage or a torn packet
    costs no more than itself."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.bad_crc = 0

    def feed(self, data: bytes) -> List[Frame]:
        self._buf += data
        frames = []
        buf = self._buf
        while True:
            start = buf.find(PREAMBLE)
            if start < 0:
                # Keep a trailing AA or AA AA: it may start a preamble.
                keep = 0
                while keep < min(2, len(buf)) and buf[-1 - keep] == 0xAA:
                    keep += 1
                del buf[:len(buf) - keep]
                break
            del buf[:start]
            # Runs of AA longer than three: the preamble is the last three.
            while len(buf) > 3 and buf[3] == 0xAA:
                del buf[0]
            if len(buf) < 6:
                break
            size = buf[4] | (buf[5] << 8)
            total = 6 + size + 2
            if len(buf) < total:
                break
            got = buf[total - 2] | (buf[total - 1] << 8)
            if crc16(bytes(buf[:total - 2])) == got:
                frames.append(Frame(buf[3], bytes(buf[6:total - 2])))
                del buf[:total]
            else:
                self.bad_crc += 1
                del buf[0]
        return frames


class Reply(NamedTuple):
    """An answer: its command ID, its status and the bytes after it."""

    cmd: int
    status: int
    params: bytes

    @property
    def status_name(self) -> str:
        return status_name(self.status)


def _reply(frame: Frame) -> Reply:
    if len(frame.payload) < 2:
        # Every answer starts with a status; a shorter one is malformed.
        return Reply(frame.cmd, Status.E_CMD_FORMAT_ERROR, b"")
    return Reply(frame.cmd, struct.unpack_from("<H", frame.payload)[0],
                 frame.payload[2:])


def _f32(data: bytes, offset: int = 0) -> float:
    value: float = struct.unpack_from("<f", data, offset)[0]
    return value


def _need(reply: Reply, n: int) -> bytes:
    if len(reply.params) < n:
        raise WsgError(reply.cmd, Status.E_CMD_FORMAT_ERROR, reply.params)
    return reply.params


def _addr(addr: Union[str, Tuple[str, int]],
          default_host: str = "127.0.0.1") -> Tuple[str, int]:
    """("host", port) from "host:port", ":port", "port" or a tuple."""
    if isinstance(addr, tuple):
        return addr[0], int(addr[1])
    host, sep, port = str(addr).rpartition(":")
    return (host or default_host) if sep else default_host, int(port)


class Pending:
    """A motion command that was accepted (E_CMD_PENDING) and whose final
    result has not been read yet. ``wait()`` reads it."""

    def __init__(self, gripper: "Gripper", cmd: int):
        self._gripper = gripper
        self.cmd = cmd
        self.reply: Optional[Reply] = None

    def wait(self, timeout: Optional[float] = None) -> Reply:
        """The final result (E_SUCCESS) or WsgError; WsgTimeout if it has
        not come within timeout seconds (default: the gripper's
        motion_timeout). With simulated time paused it comes only once the
        time is stepped far enough."""
        if self.reply is None:
            if timeout is None:
                timeout = self._gripper.motion_timeout
            reply = self._gripper._final(self, timeout)
        else:
            reply = self.reply
        if reply.status != Status.E_SUCCESS:
            raise WsgError(reply.cmd, reply.status, reply.params)
        return reply

    def done(self) -> bool:
        """Whether the final result is here, without waiting for it."""
        if self.reply is None:
            try:
                self._gripper._final(self, 0.0, block=False)
            except WsgTimeout:
                return False
        return True


class Gripper:
    """A connection to a WSG gripper, over TCP (default) or UDP.

    TCP: ``Gripper("127.0.0.1:1000")``. UDP: ``Gripper("127.0.0.1:1500",
    transport="udp", answer_port=1501)``: the gripper sends its answers to
    the sender's address at its configured remote port, so the client
    receives on a socket bound to that port.

    ``timeout`` bounds the wait for an answer to any command,
    ``motion_timeout`` the wait for a motion's final result.
    """

    def __init__(self, addr: Union[str, Tuple[str, int]] = "127.0.0.1:1000",
                 *, transport: str = "tcp", answer_port: Optional[int] = None,
                 timeout: float = 5.0, motion_timeout: float = 60.0):
        self.addr = _addr(addr)
        self.transport = transport
        self.timeout = timeout
        self.motion_timeout = motion_timeout
        self._parser = FrameParser()
        self._frames: List[Frame] = []
        # Motions answered E_CMD_PENDING whose final result has not come,
        # by ID: the next answer with that ID other than E_CMD_PENDING is
        # theirs, whenever it arrives.
        self._pending: Dict[int, Pending] = {}
        self._announced = False
        self._closed = False
        if transport == "tcp":
            self._sock = socket.create_connection(self.addr, timeout=timeout)
            # Requests go out at once, one segment each, as drivers do.
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._rsock = self._sock
        elif transport == "udp":
            if answer_port is None:
                raise ValueError("UDP needs answer_port: the port the "
                                 "gripper sends its answers to")
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._rsock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                self._rsock.bind((self.addr[0], answer_port))
            except OSError:
                self._sock.close()
                self._rsock.close()
                raise
        else:
            raise ValueError("transport is tcp or udp, not %r" % transport)

    # ---- life cycle ----

    def __enter__(self) -> "Gripper":
        return self

    def __exit__(self, exc_type: Optional[Type[BaseException]],
                 exc: Optional[BaseException],
                 tb: Optional[TracebackType]) -> None:
        self.close()

    def close(self) -> None:
        """Over TCP, announce the close (07h) and wait briefly for its
        answer, so the gripper reads it before the connection ends and does
        not go into FAST STOP; then close. Closing twice is harmless, and a
        connection the gripper already closed is just closed."""
        if self._closed:
            return
        if self.transport == "tcp" and not self._announced:
            try:
                self.disconnect(timeout=1.0)
            except (OSError, WsgError, WsgTimeout):
                pass
        self._closed = True
        self._sock.close()
        if self._rsock is not self._sock:
            self._rsock.close()

    @property
    def closed(self) -> bool:
        return self._closed

    # ---- sending and receiving ----

    def send(self, cmd: int, payload: bytes = b"") -> None:
        """Send one packet, in one send() call (some grippers' readers, and
        their drivers, expect a packet to arrive whole)."""
        pkt = encode_frame(cmd, payload)
        # A non-blocking poll (Pending.done) may have left the timeout at 0.
        self._sock.settimeout(self.timeout)
        if self.transport == "udp":
            self._sock.sendto(pkt, self.addr)
        else:
            self._sock.sendall(pkt)

    def _read_frame(self, deadline: float, block: bool = True
                    ) -> Optional[Frame]:
        while not self._frames:
            left = deadline - time.monotonic()
            if not block:
                left = 0.0
            elif left <= 0:
                return None
            self._rsock.settimeout(left if left > 0 else 0.0)
            try:
                if self.transport == "udp":
                    data, peer = self._rsock.recvfrom(65536)
                    if peer[0] != self.addr[0]:
                        continue  # only the gripper's answers count
                    # Each datagram stands alone: no packet spans two.
                    self._parser = FrameParser()
                else:
                    data = self._rsock.recv(65536)
            except (socket.timeout, BlockingIOError):
                if not block:
                    return None
                continue
            if not data:
                raise ConnectionError("the gripper closed the connection")
            self._frames.extend(self._parser.feed(data))
            if not block and not self._frames:
                return None
        return self._frames.pop(0)

    def receive(self, timeout: Optional[float] = None) -> Optional[Reply]:
        """The next packet from the gripper, whatever its ID (a stream's
        value, say), or None if none comes within timeout seconds (default:
        the client's timeout). For use with send() at the protocol level."""
        deadline = time.monotonic() + (self.timeout if timeout is None
                                       else timeout)
        frame = self._read_frame(deadline)
        return None if frame is None else self._route(frame)

    def _route(self, frame: Frame) -> Reply:
        """Hand a final result to the motion that is owed it."""
        r = _reply(frame)
        if r.cmd in self._pending and r.status != Status.E_CMD_PENDING:
            self._pending.pop(r.cmd).reply = r
        return r

    def _final(self, pending: Pending, timeout: float,
               block: bool = True) -> Reply:
        """Read until pending has its final result and return it;
        WsgTimeout if it has not come within timeout (block=False: only
        what is there now, and WsgTimeout if that is not it)."""
        deadline = time.monotonic() + timeout
        while pending.reply is None:
            frame = self._read_frame(deadline, block)
            if frame is None:
                raise WsgTimeout("no final result for %s within %.1f s"
                                 % (_cmd_label(pending.cmd), timeout))
            self._route(frame)
        return pending.reply

    # With wait=True (the default) the answer is always a Reply: the
    # overloads tell a type checker so, and only wait=False callers need
    # to tell a Pending apart.
    @overload
    def request(self, cmd: int, payload: bytes = b"",
                timeout: Optional[float] = None,
                wait: "Literal[True]" = True) -> Reply: ...

    @overload
    def request(self, cmd: int, payload: bytes = b"",
                timeout: Optional[float] = None, *,
                wait: bool) -> Union[Reply, Pending]: ...

    def request(self, cmd: int, payload: bytes = b"",
                timeout: Optional[float] = None,
                wait: bool = True) -> Union[Reply, Pending]:
        """Send a command and return its answer, whatever its status. For a
        motion answered E_CMD_PENDING, wait=True waits for the final result
        (up to motion_timeout); wait=False returns a Pending at once.
        Frames with other IDs (auto-update streams) are skipped."""
        if self._closed:
            raise ConnectionError("the client is closed")
        cmd = int(cmd)
        if cmd in self._pending:
            # Its answer could not be told from the owed final result,
            # which has the same ID. (To see E_ALREADY_RUNNING, send the
            # second motion from another client.)
            raise RuntimeError("%s: the final result of the previous one "
                               "is still owed: wait() for it first"
                               % _cmd_label(cmd))
        self.send(cmd, payload)
        answer_timeout = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + answer_timeout
        while True:
            frame = self._read_frame(deadline)
            if frame is None:
                raise WsgTimeout("no answer to %s within %.1f s"
                                 % (_cmd_label(cmd), answer_timeout))
            r = self._route(frame)
            if r.cmd != cmd:
                continue
            if r.status == Status.E_CMD_PENDING:
                pending = Pending(self, cmd)
                self._pending[cmd] = pending
                if not wait:
                    return pending
                return self._final(pending, self.motion_timeout
                                   if timeout is None else timeout)
            return r

    def command(self, cmd: int, payload: bytes = b"",
                timeout: Optional[float] = None) -> bytes:
        """Send a command, wait for its (final) answer, return its
        parameters; WsgError on any status but E_SUCCESS."""
        r = self.request(cmd, payload, timeout)
        if r.status != Status.E_SUCCESS:
            raise WsgError(r.cmd, r.status, r.params)
        return r.params

    def _motion(self, cmd: int, payload: bytes, wait: bool,
                timeout: Optional[float]) -> Optional[Pending]:
        r = self.request(cmd, payload, timeout, wait=wait)
        if isinstance(r, Pending):
            return r
        if r.status != Status.E_SUCCESS:
            raise WsgError(r.cmd, r.status, r.params)
        return None

    # ---- motion (chapter 3.2) ----

    def home(self, direction: Union[None, int, str] = None, *,
             wait: bool = True, timeout: Optional[float] = None
             ) -> Optional[Pending]:
        """Homing (20h): direction None (the configured default),
        "positive" or "negative" (or 0, 1, 2). With wait=False, returns a
        Pending once the gripper has accepted the command."""
        names: Dict[Optional[str], int] = {
            None: 0, "default": 0, "positive": 1, "pos": 1,
            "negative": 2, "neg": 2}
        d = direction if isinstance(direction, int) else names.get(direction)
        if d is None or d not in (0, 1, 2):
            raise ValueError("homing direction: positive, negative or None")
        return self._motion(Cmd.HOMING, bytes([d]), wait, timeout)

    def move(self, width: float, speed: float, *, relative: bool = False,
             stop_on_block: bool = False, wait: bool = True,
             timeout: Optional[float] = None) -> Optional[Pending]:
        """Preposition Fingers (21h) to width mm at speed mm/s."""
        flags = (1 if relative else 0) | (2 if stop_on_block else 0)
        return self._motion(Cmd.PREPOSITION,
                            struct.pack("<Bff", flags, width, speed),
                            wait, timeout)

    preposition = move

    def grasp(self, width: float, speed: float, *, wait: bool = True,
              timeout: Optional[float] = None) -> Optional[Pending]:
        """Grasp Part (25h) of nominal width mm at speed mm/s."""
        return self._motion(Cmd.GRASP, struct.pack("<ff", width, speed),
                            wait, timeout)

    def release(self, width: float, speed: float, *, wait: bool = True,
                timeout: Optional[float] = None) -> Optional[Pending]:
        """Release Part (26h): open to width mm at speed mm/s."""
        return self._motion(Cmd.RELEASE, struct.pack("<ff", width, speed),
                            wait, timeout)

    def stop(self) -> None:
        """Stop (22h)."""
        self.command(Cmd.STOP)

    def fast_stop(self) -> None:
        """Issue FAST STOP (23h): the gripper refuses motion until ack()."""
        self.command(Cmd.FAST_STOP)

    def ack(self) -> None:
        """Acknowledge Error (24h), key "ack": clears FAST STOP."""
        self.command(Cmd.ACK_FAST_STOP, b"ack")

    # ---- settings (chapter 3.3) ----

    def set_acceleration(self, mm_s2: float) -> float:
        """Set Acceleration (30h); the gripper clamps to its limits."""
        self.command(Cmd.SET_ACCELERATION, struct.pack("<f", mm_s2))
        return self.get_acceleration()

    def get_acceleration(self) -> float:
        """Get Acceleration (31h) in mm/s²."""
        return _f32(self.command(Cmd.GET_ACCELERATION))

    def set_force_limit(self, newton: float) -> float:
        """Set Force Limit (32h); the gripper clamps to its limits."""
        self.command(Cmd.SET_FORCE_LIMIT, struct.pack("<f", newton))
        return self.get_force_limit()

    def get_force_limit(self) -> float:
        """Get Force Limit (33h) in N."""
        return _f32(self.command(Cmd.GET_FORCE_LIMIT))

    def set_soft_limits(self, minus: float, plus: float) -> None:
        """Set Soft Limits (34h), in mm."""
        self.command(Cmd.SET_SOFT_LIMITS, struct.pack("<ff", minus, plus))

    def get_soft_limits(self) -> Optional[Tuple[float, float]]:
        """Get Soft Limits (35h): (minus, plus) in mm, None when none are
        set (the gripper answers E_NOT_AVAILABLE then)."""
        r = self.request(Cmd.GET_SOFT_LIMITS)
        if r.status == Status.E_NOT_AVAILABLE:
            return None
        if r.status != Status.E_SUCCESS:
            raise WsgError(r.cmd, r.status, r.params)
        p = _need(r, 8)
        return _f32(p, 0), _f32(p, 4)

    def clear_soft_limits(self) -> None:
        """Clear Soft Limits (36h)."""
        self.command(Cmd.CLEAR_SOFT_LIMITS)

    def overdrive(self, on: bool) -> None:
        """Overdrive Mode (37h): force limits up to the overdrive force."""
        self.command(Cmd.OVERDRIVE, bytes([1 if on else 0]))

    def tare(self) -> None:
        """Tare Force Sensor (38h); E_NOT_AVAILABLE without force
        measurement fingers."""
        self.command(Cmd.TARE)

    # ---- the fingers (later firmware's 60h..63h, 70h..73h) ----
    # Finger 0 is the commands' finger 1 (60h..63h), finger 1 their
    # finger 2 (70h..73h); the 4.x style, no index byte (docs/fingers.md).

    @staticmethod
    def _finger_cmd(finger: int, first: int) -> int:
        if finger not in (0, 1):
            raise ValueError("a finger is 0 or 1")
        return first + 0x10 * finger

    def finger_info(self, finger: int) -> Tuple[int, int]:
        """Get Finger Info (60h/70h): (type, size of its data)."""
        p = self.command(self._finger_cmd(finger, Cmd.GET_FINGER1_INFO))
        return p[0], int(struct.unpack_from("<H", p, 1)[0])

    def finger_flags(self, finger: int) -> FingerFlag:
        """Get Finger Flags (61h/71h): FingerFlag's bits (D0 powered, D1
        data, D2 fault, D3 contact, D4 UART, D5 SPI, D6 overrun)."""
        p = self.command(self._finger_cmd(finger, Cmd.GET_FINGER1_FLAGS))
        return FingerFlag(struct.unpack_from("<H", p)[0])

    def finger_power(self, finger: int, on: bool) -> None:
        """Finger Power Control (62h/72h)."""
        self.command(self._finger_cmd(finger, Cmd.FINGER1_POWER),
                     bytes([1 if on else 0]))

    def finger_data(self, finger: int) -> bytes:
        """Get Finger Data (63h/73h): as many bytes as 60h's size."""
        return self.command(self._finger_cmd(finger, Cmd.GET_FINGER1_DATA))

    def finger_force(self, finger: int) -> float:
        """A force measurement finger's 63h: its force in N (tared)."""
        return float(struct.unpack("<f", self.finger_data(finger))[0])

    def finger_cells(self, finger: int) -> List[int]:
        """A DSA pad's 63h: 84 cells, 6 columns by 14 rows, row-major."""
        p = self.finger_data(finger)
        return list(struct.unpack("<%dH" % (len(p) // 2), p))

    # ---- state (chapter 3.4) and system (3.5) ----

    def system_state(self) -> SystemFlag:
        """Get System State (40h): the flags, one-time read."""
        p = self.command(Cmd.GET_SYSTEM_STATE)
        return SystemFlag(struct.unpack_from("<I", p)[0])

    def grasp_state(self) -> Union[GraspState, int]:
        """Get Grasping State (41h); the number itself for one the
        protocol does not name."""
        p = self.command(Cmd.GET_GRASP_STATE)
        try:
            return GraspState(p[0])
        except ValueError:
            return p[0]

    def grasp_stats(self, reset: bool = False) -> GraspStats:
        """Get Grasping Statistics (42h): total, no part, lost part."""
        p = self.command(Cmd.GET_GRASP_STATS, bytes([1 if reset else 0]))
        return GraspStats(*struct.unpack_from("<IHH", p))

    def width(self) -> float:
        """Get Opening Width (43h) in mm."""
        return _f32(self.command(Cmd.GET_WIDTH))

    def speed(self) -> float:
        """Get Speed (44h) in mm/s, positive while opening."""
        return _f32(self.command(Cmd.GET_SPEED))

    def force(self) -> float:
        """Get Force (45h) in N."""
        return _f32(self.command(Cmd.GET_FORCE))

    def temperature(self) -> float:
        """Get Temperature (46h) in °C (sent as int16 of 0.1 °C)."""
        p = self.command(Cmd.GET_TEMPERATURE)
        tenths: int = struct.unpack_from("<h", p)[0]
        return tenths / 10

    def system_info(self) -> SystemInfo:
        """Get System Information (50h)."""
        p = self.command(Cmd.GET_SYSTEM_INFO)
        typ, hw, sw, sn = struct.unpack_from("<BBHI", p)
        fw = "%d.%d.%d" % (sw >> 12, (sw >> 8) & 15, (sw >> 4) & 15)
        return SystemInfo(typ, _DEVICE_TYPES.get(typ, "?"), hw, fw, sn)

    def set_tag(self, text: str) -> None:
        """Set Device Tag (51h); "" removes it."""
        self.command(Cmd.SET_DEVICE_TAG, text.encode("ascii"))

    def tag(self) -> Optional[str]:
        """Get Device Tag (52h); None when no tag is set."""
        r = self.request(Cmd.GET_DEVICE_TAG)
        if r.status == Status.E_NOT_AVAILABLE:
            return None
        if r.status != Status.E_SUCCESS:
            raise WsgError(r.cmd, r.status, r.params)
        return r.params.rstrip(b"\0").decode("ascii")

    def limits(self) -> SystemLimits:
        """Get System Limits (53h)."""
        p = self.command(Cmd.GET_SYSTEM_LIMITS)
        return SystemLimits(*struct.unpack_from("<8f", p))

    def loop(self, data: bytes) -> bytes:
        """Loop (06h): the gripper echoes data back."""
        return self.command(Cmd.LOOP, bytes(data))

    def disconnect(self, timeout: Optional[float] = None) -> None:
        """Disconnect Announcement (07h). The connection's later commands
        are refused (E_ACCESS_DENIED); close() sends it by itself."""
        self._announced = True
        self.command(Cmd.DISCONNECT, timeout=timeout)


def _num(v: float) -> str:
    """A number for a control line, exact ("%g" would round to 6 digits)."""
    text = repr(float(v))
    return text[:-2] if text.endswith(".0") else text


class ControlError(Exception):
    """The control channel answered ``error ...``."""

    def __init__(self, line: str, reason: str):
        self.line = line
        self.reason = reason
        super().__init__("%s: %s" % (line, reason))


class Control:
    """A connection to wsgemu's control channel (``--control``)."""

    def __init__(self, addr: Union[str, Tuple[str, int]],
                 timeout: float = 5.0):
        self.addr = _addr(addr)
        self.timeout = timeout
        self._sock = socket.create_connection(self.addr, timeout=timeout)
        self._buf = b""
        #: Byte offset in the script's output where the last
        #: script_output() or script_output_new() stopped reading.
        self.script_output_end = 0
        #: Bytes the last of them could not return: printed, but already
        #: pushed out of the daemon's ring (it keeps the last 64 KiB).
        self.script_output_lost = 0

    def __enter__(self) -> "Control":
        return self

    def __exit__(self, exc_type: Optional[Type[BaseException]],
                 exc: Optional[BaseException],
                 tb: Optional[TracebackType]) -> None:
        self.close()

    def close(self) -> None:
        self._sock.close()

    def _line(self) -> str:
        deadline = time.monotonic() + self.timeout
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise WsgTimeout("no answer on the control channel within "
                                 "%.1f s" % self.timeout)
            self._sock.settimeout(left)
            try:
                data = self._sock.recv(65536)
            except socket.timeout:
                continue
            if not data:
                raise ConnectionError("the control channel was closed")
            self._buf += data
        line, _, self._buf = self._buf.partition(b"\n")
        # A script's output and error come as the bytes it printed, which
        # need not be UTF-8: kept as surrogates, so script_output() can
        # have the exact bytes back.
        return line.decode("utf-8", "surrogateescape").rstrip("\r")

    def command(self, line: str) -> str:
        """Send one command line; the text after ``ok`` (maybe empty), or
        ControlError with the reason after ``error``."""
        if "\n" in line:
            raise ValueError("one command per line")
        self._sock.sendall(line.encode("utf-8") + b"\n")
        answer = self._line()
        word, _, rest = answer.partition(" ")
        if word == "ok":
            return rest
        if word == "error":
            raise ControlError(line, _text(rest))
        raise ConnectionError("unexpected control answer %r" % answer)

    # The world between the fingers.

    def part(self, width: Optional[float], stiffness: Optional[float] = None
             ) -> str:
        """A part of width mm (stiffness N/mm) between the fingers; None
        takes it away (a held part is then lost)."""
        if width is None:
            return self.command("part none")
        if stiffness is None:
            return self.command("part " + _num(width))
        return self.command("part %s %s" % (_num(width), _num(stiffness)))

    def fingers(self) -> List[Dict[str, Any]]:
        """Both fingers as the channel's `finger` has them (kind, type,
        size, flags, powered, force, model)."""
        return list(json.loads(self.command("finger")))

    def finger(self, finger: int, kind: str) -> str:
        """Fit finger 0 or 1: none, generic, fmf, dsa, or device:FILE (a
        device model)."""
        if kind.startswith("device:"):
            return self.command("finger %d device %s" % (finger, kind[7:]))
        return self.command("finger %d %s" % (finger, kind))

    def finger_cells(self, finger: int) -> List[int]:
        """A DSA pad's frame as the channel reads it (zeros otherwise)."""
        return [int(x) for x in json.loads(
            self.command("finger %d cells" % finger))]

    def obstacle(self, width: Optional[float]) -> str:
        """Something rigid that blocks the fingers at width mm; None
        removes it."""
        return self.command("obstacle none" if width is None
                            else "obstacle " + _num(width))

    def object(self, kind: Optional[str], *size: float,
               mass: Optional[float] = None,
               friction: Optional[float] = None) -> str:
        """With --physics mujoco: place an object between the fingers,
        kind "box" (width, depth, height), "cylinder" (diameter, length) or
        "sphere" (diameter), sizes in mm, mass in kg, friction (defaults
        0.1 kg and 1; friction needs a mass); None removes it. Where it is
        now: state()["object"]. ControlError on the built-in plant."""
        if kind is None:
            return self.command("object none")
        if friction is not None and mass is None:
            raise ValueError("a friction needs a mass before it")
        words = ["object", kind, *(_num(v) for v in size)]
        if mass is not None:
            words.append(_num(mass))
        if friction is not None:
            words.append(_num(friction))
        return self.command(" ".join(words))

    def pull(self, newtons: float) -> str:
        """With --physics mujoco: pull the object out of the fingers with
        that force (N; 0 stops pulling)."""
        return self.command("pull " + _num(newtons))

    def fault(self, name: str, on: bool = True) -> str:
        """temp-warning, temp-fault, power, current, finger: on or off."""
        return self.command("fault %s %s" % (name, "on" if on else "off"))

    # Simulated time.

    def time(self) -> float:
        """Simulated time now, in seconds."""
        return float(self.command("time"))

    def time_scale(self, x: float) -> str:
        return self.command("time scale " + _num(x))

    def pause(self) -> str:
        return self.command("time pause")

    def resume(self) -> str:
        return self.command("time resume")

    def step(self, ms: float) -> float:
        """While paused, advance simulated time by exactly ms; the
        simulated time after it, in seconds. Whatever packets the steps
        caused were sent before this returns."""
        return float(self.command("time step " + _num(ms)))

    # The emulator.

    def state(self) -> Dict[str, Any]:
        """The gripper's state as the emulator sees it (parsed JSON)."""
        return _json_object(self.command("state"))

    def stats(self) -> Dict[str, Any]:
        """The loop's figures (parsed JSON)."""
        return _json_object(self.command("stats"))

    def drop(self) -> str:
        """Close every TCP connection without 07h (FAST STOP follows)."""
        return self.command("drop")

    def reset(self) -> str:
        """A power cycle: defaults, not referenced, motions aborted."""
        return self.command("reset")

    def gripper(self, n: Optional[int] = None) -> int:
        """In a fleet: select gripper n for this client's commands; without
        n, the one selected."""
        text = self.command("gripper" if n is None else "gripper %d" % n)
        return int(text.split()[1])  # "gripper N of M"

    # Scripts on the gripper (the selected one of a fleet).

    def script_run(self, path: Union[str, "os.PathLike[str]"]) -> str:
        """Run the Lua script at path on the gripper. A relative path is
        made absolute here, from this process's working directory (the
        daemon would take it from its own). ControlError when the file
        cannot be read, a script runs already (script_stop() first), or
        the script fails before its first wait (its error in
        ``.reason``). ValueError for a path with a blank or a line break,
        which the channel's line cannot carry."""
        path = os.path.abspath(os.fspath(path))
        if any(ch.isspace() for ch in path):
            raise ValueError("the control channel splits its lines at "
                             "blanks: a script path cannot hold one: %r"
                             % path)
        return self.command("script run " + path)

    def script_stop(self) -> bool:
        """End the running script (its IDs are unregistered, a speed-mode
        motion it left is stopped); False if none was running."""
        return self.command("script stop") == "script stopped"

    def script_status(self) -> Dict[str, Any]:
        """The script's state (parsed JSON): ``running``, ``failed``,
        ``error`` (None or the message of the error that ended it),
        ``file`` (the absolute path, None before any run), ``state``
        ("reading", "sleeping", "runnable", "running" or "stopped"),
        ``registered`` (the command IDs it took, as numbers),
        ``memory``, ``memory_max`` (bytes) and ``preempted`` (how often
        its time slice ran out)."""
        status = _json_object(self.command("script status"))
        for key in ("error", "file"):
            if isinstance(status.get(key), str):
                status[key] = _text(status[key])
        return status

    def script_output(self, from_: int = 0) -> str:
        """What the script printed from byte offset from_ on, up to what
        it had printed when this was called (the daemon answers at most
        about 1 KiB a line, so this asks until it has it all). The daemon
        keeps the last 64 KiB: bytes older than that are skipped and
        counted in ``script_output_lost``. Decoded as UTF-8, a byte that
        is not as U+FFFD. Afterwards ``script_output_end`` is the offset
        after the text, where script_output_new() goes on."""
        if from_ < 0:
            raise ValueError("from_ is a byte offset, not %r" % (from_,))
        data, lost, pos = bytearray(), 0, int(from_)
        stop: Optional[int] = None
        while True:
            chunk = json.loads(self.command("script output %d" % pos))
            lost += chunk["lost"]
            data += chunk["text"].encode("utf-8", "surrogateescape")
            if stop is None:
                # What was there at the first answer: a script that
                # prints on cannot keep this loop going.
                stop = chunk["end"]
            if chunk["next"] >= stop or chunk["next"] == chunk["from"]:
                pos = chunk["next"]
                break
            pos = chunk["next"]
        self.script_output_end = pos
        self.script_output_lost = lost
        return data.decode("utf-8", "replace")

    def script_output_new(self) -> str:
        """What the script printed since this client's last
        script_output() or script_output_new() (all of it, the first
        time): ``script_output(script_output_end)``. The offset is this
        client's: after gripper(n) selects another gripper of a fleet,
        start again with script_output()."""
        return self.script_output(self.script_output_end)


def _json_object(text: str) -> Dict[str, Any]:
    """A JSON object the channel answered, as a dict; ControlError for
    anything else (a daemon that does not speak this channel)."""
    value = json.loads(text)
    if not isinstance(value, dict):
        raise ControlError(text, "not a JSON object")
    return value


def _text(s: str) -> str:
    """A string of the channel's JSON as readable text: bytes that were
    not UTF-8 (kept as surrogates by Control._line) as U+FFFD."""
    return s.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
