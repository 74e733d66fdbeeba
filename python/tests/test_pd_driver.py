"""A UMI-style driver against a position controller running as a script on
the gripper (tests/scripts/pd_control.lua, the project's own), as the
research stacks that upload such a script use it (SCRIPTING.md, "How
drivers use scripts"): connect over TCP, acknowledge (24h), home (20h, its
final result waited for), one B0h with payload 00, then B1h at 30 Hz with
a target position and velocity, the PD gains and two force limits (25
bytes). Every answer must be exactly 19 bytes with status E_SUCCESS, as
the driver rejects anything else: the state's lowest byte (bit 1
"moving"), then position, speed, motor force and the script's clock as
float32.

Tracking and contact are checked in lockstep: simulated time paused and
stepped 33 ms between requests through the control channel, so the
controller sees exactly the same loop on any machine and the bounds can be
tight. One run at 30 Hz of wall-clock time shows the same driver working
as it would against a gripper, with loose bounds that hold on a loaded
machine.
"""

import math
import os
import struct
import time
from typing import List, NamedTuple

import pytest

from wsgemu import Gripper, Reply, Status, SystemFlag

SCRIPT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "tests", "scripts", "pd_control.lua")

pytestmark = [
    # The marker's path is relative to this file: the wsgemu source tree.
    pytest.mark.wsgemu_script("../../tests/scripts/pd_control.lua"),
    # Homing at ten times real time; the lockstep tests pause the clock
    # anyway, the real-time one sets scale 1 after homing.
    pytest.mark.wsgemu_args("--time-scale", "10"),
    pytest.mark.skipif(not os.path.isfile(SCRIPT),
                       reason="not in the wsgemu source tree: no %s"
                       % SCRIPT),
]

CMD_STATE, CMD_PD = 0xB0, 0xB1
REPLY_LEN = 19
TICK_MS = 33  # 30 Hz on the emulator's 1 ms grid
KP, KD = 15.0, 0.002  # 1/s, s: the speed command per mm and per mm/s
TRAVEL_FORCE, BLOCKED_FORCE = 60.0, 15.0  # N
PART_STIFFNESS = 50.0  # N/mm: the control channel's default for a part


class PdState(NamedTuple):
    """One answer of the script."""

    flags: int  # the lowest byte of the system state flags
    position: float  # mm
    speed: float  # mm/s
    force: float  # N, from the motor current
    time: float  # s, the script's clock (simulated time)

    @property
    def moving(self) -> bool:
        return bool(self.flags & SystemFlag.SF_MOVING)

    @property
    def blocked(self) -> bool:
        return bool(self.flags & SystemFlag.SF_BLOCKED_MINUS)


class PdDriver:
    """The driver's side: the start sequence and the two custom commands,
    with the driver's checks on every answer."""

    def __init__(self, gripper: Gripper):
        self.g = gripper

    def start(self) -> PdState:
        self.g.ack()
        self.g.home()  # waits for the final result
        return self.state()

    def state(self) -> PdState:
        return self._decode(self.g.request(CMD_STATE, b"\x00"))

    def pd(self, position: float, velocity: float = 0.0) -> PdState:
        payload = struct.pack("<B6f", 0, position, velocity, KP, KD,
                              TRAVEL_FORCE, BLOCKED_FORCE)
        assert len(payload) == 25
        return self._decode(self.g.request(CMD_PD, payload))

    @staticmethod
    def _decode(r: Reply) -> PdState:
        assert r.status == Status.E_SUCCESS, r.status_name
        # The status is the first two bytes of the payload.
        assert 2 + len(r.params) == REPLY_LEN, r.params.hex()
        return PdState(r.params[0], *struct.unpack("<4f", r.params[1:]))


def _sine(t: float):
    """A target between 20 and 80 mm, period 2 s: (position, velocity)."""
    w = 2 * math.pi / 2.0
    return 50.0 + 30.0 * math.sin(w * t), 30.0 * w * math.cos(w * t)


def test_start_sequence_and_what_the_script_took(wsgemu):
    st = PdDriver(wsgemu.gripper).start()
    assert st.flags & SystemFlag.SF_REFERENCED and not st.moving
    assert st.position == pytest.approx(110.0, abs=0.01)  # homed open
    assert (st.speed, st.force) == (0.0, 0.0)
    assert st.time > 0.0
    status = wsgemu.control.script_status()
    assert status["running"] and status["registered"] == [CMD_STATE, CMD_PD]
    assert wsgemu.control.script_output() == "pd_control: B0h B1h registered\n"
    assert wsgemu.gripper.system_state() & SystemFlag.SF_SCRIPT_RUNNING


def test_malformed_requests_are_refused(wsgemu):
    g = wsgemu.gripper
    PdDriver(g).start()
    # A B1h one byte short: the script's own format error, 2 bytes, so
    # the driver fails loudly.
    r = g.request(CMD_PD, bytes(24))
    assert (r.status, r.params) == (Status.E_CMD_FORMAT_ERROR, b"")
    # An ID it did not register is the firmware's: unknown.
    assert g.request(0xB2, b"\x00").status == Status.E_CMD_UNKNOWN
    assert wsgemu.control.script_status()["running"]


def test_tracks_a_moving_target_in_lockstep(wsgemu):
    drv = PdDriver(wsgemu.gripper)
    drv.start()
    wsgemu.control.pause()
    states: List[PdState] = []
    targets = []
    for k in range(int(2.5 * 1000 / TICK_MS)):
        target = _sine(k * TICK_MS / 1000.0)
        targets.append(target[0])
        states.append(drv.pd(*target))
        wsgemu.control.step(TICK_MS)
    # The script's clock is the simulated time: one tick per request.
    for k, st in enumerate(states):
        assert st.time == pytest.approx(states[0].time + k * TICK_MS / 1000,
                                        abs=1e-4)
    # Past the first half second (the fingers come from 110 mm), the
    # fingers follow the target: a PD controller on the speed lags a
    # ramp by about v/kp (94 mm/s / 15 = 6.3 mm at the steepest).
    settled = [(st, x) for k, (st, x) in enumerate(zip(states, targets))
               if k * TICK_MS >= 500]
    errors = [st.position - x for st, x in settled]
    assert max(abs(e) for e in errors) < 8.0, errors
    rms = math.sqrt(sum(e * e for e in errors) / len(errors))
    assert rms < 5.0
    assert min(st.position for st, _ in settled) < 25.0
    assert max(st.position for st, _ in settled) > 75.0
    # "Moving" whenever the fingers move; nothing in the way, no force.
    for st in states:
        if abs(st.speed) > 1.0:
            assert st.moving, st
        assert st.force == 0.0 and not st.blocked


def test_blocks_at_a_part_with_the_blocked_force_limit(wsgemu):
    drv = PdDriver(wsgemu.gripper)
    drv.start()
    wsgemu.control.part(40)  # 40 mm wide, between the fingers
    wsgemu.control.pause()

    def hold(target, seconds):
        out = []
        for _ in range(int(seconds * 1000 / TICK_MS)):
            out.append(drv.pd(target))
            wsgemu.control.step(TICK_MS)
        return out

    free = hold(60.0, 1.0)
    assert free[-1].position == pytest.approx(60.0, abs=0.5)
    assert all(st.force == 0.0 and not st.blocked for st in free)
    # Closing on the part with a target inside it: the fingers stop at the
    # part, squeezed by the blocked force limit (not the travel one).
    closing = hold(20.0, 1.0)
    contact = [st for st in closing if st.blocked]
    assert contact, "the fingers never met the part"
    squeezed = 40.0 - BLOCKED_FORCE / PART_STIFFNESS
    for st in contact:
        assert st.position == pytest.approx(squeezed, abs=0.05)
        assert st.force == pytest.approx(BLOCKED_FORCE, abs=0.01)
        assert st.speed == 0.0
    assert max(st.force for st in closing) <= BLOCKED_FORCE + 0.01
    assert min(st.position for st in closing) >= squeezed - 0.05
    # Blocked at the end: the part is there for good.
    assert closing[-1].blocked
    state = wsgemu.control.state()
    assert state["width"] == pytest.approx(squeezed, abs=0.05)
    assert state["force"] == pytest.approx(BLOCKED_FORCE, abs=0.01)
    # Away from it again: free, no force, at the target.
    opening = hold(60.0, 1.0)
    assert not opening[-1].blocked and opening[-1].force == 0.0
    assert opening[-1].position == pytest.approx(60.0, abs=0.5)


def test_at_30_hz_in_real_time(wsgemu):
    """The driver's own loop against the running clock: loose bounds, as
    this machine may be busy (a late tick is a longer controller step)."""
    drv = PdDriver(wsgemu.gripper)
    drv.start()
    wsgemu.control.time_scale(1)
    states: List[PdState] = []
    t0 = time.monotonic()
    k = 0
    while True:
        t = time.monotonic() - t0
        if t >= 2.0:
            break
        states.append(drv.pd(*_sine(t)))
        k += 1
        time.sleep(max(0.0, t0 + k / 30.0 - time.monotonic()))
    # Then the target holds still for a second.
    t1 = time.monotonic()
    while time.monotonic() - t1 < 1.0:
        last = drv.pd(50.0)
        time.sleep(1 / 30.0)
    wall = time.monotonic() - t0
    # The script's clock only goes forward, and at time scale 1 it keeps
    # to the wall clock (within a factor of two).
    clock = [st.time for st in states]
    assert all(b > a for a, b in zip(clock, clock[1:]))
    assert 0.5 * wall < last.time - states[0].time < 2.0 * wall
    # It followed the target over most of its range, and settled on the
    # still one.
    assert min(st.position for st in states[15:]) < 35.0
    assert max(st.position for st in states[15:]) > 65.0
    assert last.position == pytest.approx(50.0, abs=1.0)
    assert abs(last.speed) < 5.0
