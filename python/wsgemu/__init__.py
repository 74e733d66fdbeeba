"""wsgemu: a Python client of the WSG gripper protocol and of the wsgemu
emulator's control channel, and a pytest plugin that runs the emulator.

- ``Gripper``: the WSG command set over TCP or UDP in human units;
- ``Control``: wsgemu's control channel (parts, faults, simulated time,
  scripts on the gripper);
- ``Emulator``: start and stop a wsgemu daemon on free ports;
- the ``wsgemu`` pytest fixture (``wsgemu.plugin``), loaded automatically.
"""

from .client import (Cmd, Control, ControlError, FingerFlag, Frame,
                     FrameParser, GraspState, GraspStats, Gripper, Pending, Reply, Status,
                     SystemFlag, SystemInfo, SystemLimits, WsgError,
                     WsgTimeout, crc16, encode_frame, status_name)
from .daemon import (AttachedEmulator, DaemonError, Emulator, bundled_binary,
                     find_binary, free_udp_port, parse_attach,
                     parse_ready_line)

__version__ = "0.1.0"

__all__ = [
    "AttachedEmulator", "Cmd", "Control", "ControlError", "DaemonError",
    "Emulator", "FingerFlag", "Frame", "bundled_binary", "free_udp_port", "parse_attach",
    "FrameParser", "GraspState", "GraspStats", "Gripper", "Pending", "Reply",
    "Status", "SystemFlag", "SystemInfo", "SystemLimits", "WsgError",
    "WsgTimeout", "crc16", "encode_frame", "find_binary", "parse_ready_line",
    "status_name",
]
