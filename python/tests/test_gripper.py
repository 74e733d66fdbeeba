"""The Gripper and Control clients against the real daemon, through the
wsgemu fixture: the manual's situations (homing, preposition, a grasp that
holds, a grasp with no part, an error status, FAST STOP and its
acknowledge, soft limits, the settings' clamping) and the control
channel's simulated time, which is paused and stepped where a test needs
exact timing. Expected values come from the manual, docs/behaviour.md and
the WSG 50 model's figures in the project's NOTES (stroke 110 mm, speed
5..420 mm/s, acceleration 100..5000 mm/s², force 5..80 N, overdrive 120 N,
default force limit 40 N)."""

import socket
import struct
import time

import pytest

from wsgemu import (Cmd, ControlError, FingerFlag, GraspState, Status,
                    SystemFlag, WsgError, WsgTimeout)

STROKE = 110.0  # WSG 50

# Simulated time runs ten times faster than real time: the same motions,
# the same end states, a quicker suite. Tests that need exact timing pause
# and step it.
pytestmark = pytest.mark.wsgemu_args("--time-scale", "10")


def _homed(wsgemu):
    g = wsgemu.gripper
    g.home()
    return g


def test_homing_references_the_gripper_at_the_end_stop(wsgemu):
    g = wsgemu.gripper
    assert not g.system_state() & SystemFlag.SF_REFERENCED
    assert g.width() == pytest.approx(55.0)  # as shipped: half open
    g.home()  # waits through E_CMD_PENDING for E_SUCCESS
    assert g.system_state() & SystemFlag.SF_REFERENCED
    # Default homing direction positive: the fingers end fully open.
    assert g.width() == pytest.approx(STROKE, abs=0.01)
    assert g.grasp_state() == GraspState.IDLE


def test_homing_negative_ends_closed(wsgemu):
    g = wsgemu.gripper
    g.home("negative")
    assert g.width() == pytest.approx(0.0, abs=0.01)


def test_move_before_homing_is_not_initialized(wsgemu):
    # Manual 3.2.2: E_NOT_INITIALIZED, "Issue a Homing command, first."
    with pytest.raises(WsgError) as e:
        wsgemu.gripper.move(50.0, 100.0)
    assert e.value.status == Status.E_NOT_INITIALIZED
    assert e.value.status_name == "E_NOT_INITIALIZED"
    assert e.value.cmd == Cmd.PREPOSITION
    assert "E_NOT_INITIALIZED" in str(e.value)
    # The command failed: the gripper says so in its flags (SF_CMD_FAILURE).
    assert wsgemu.gripper.system_state() & SystemFlag.SF_CMD_FAILURE


def test_preposition_absolute_and_relative(wsgemu):
    g = _homed(wsgemu)
    g.move(60.0, 100.0)
    assert g.width() == pytest.approx(60.0, abs=0.01)
    assert g.system_state() & SystemFlag.SF_TARGET_POS_REACHED
    g.preposition(-15.0, 100.0, relative=True)
    assert g.width() == pytest.approx(45.0, abs=0.01)
    assert g.speed() == pytest.approx(0.0)
    assert g.grasp_state() == GraspState.IDLE


def test_grasp_of_a_placed_part_holds_it(wsgemu):
    g = _homed(wsgemu)
    assert wsgemu.control.part(40) == "part 40 50"  # 40 mm, 50 N/mm
    g.grasp(40.0, 100.0)
    assert g.grasp_state() == GraspState.HOLDING
    # Held with the force limit (default 40 N), squeezed by that force
    # over the part's stiffness: 40 N / 50 N/mm = 0.8 mm.
    assert g.force() == pytest.approx(40.0, abs=0.01)
    assert g.width() == pytest.approx(39.2, abs=0.01)
    assert g.grasp_stats() == (1, 0, 0)
    state = wsgemu.control.state()
    assert state["grasp_state_name"] == "holding"
    assert state["stats"] == {"total": 1, "no_part": 0, "lost_part": 0}
    g.release(70.0, 100.0)
    assert g.grasp_state() == GraspState.IDLE
    assert g.width() == pytest.approx(70.0, abs=0.01)
    assert g.force() == pytest.approx(0.0)


def test_grasp_with_no_part_fails(wsgemu):
    g = _homed(wsgemu)
    # Nothing between the fingers: they close through the clamping travel.
    with pytest.raises(WsgError) as e:
        g.grasp(40.0, 100.0)
    assert e.value.status_name == "E_CMD_FAILED"
    assert g.grasp_state() == GraspState.NO_PART
    assert g.grasp_stats().no_part == 1


def test_part_taken_away_while_held_is_lost(wsgemu):
    g = _homed(wsgemu)
    wsgemu.control.part(30)
    g.grasp(30.0, 100.0)
    assert g.grasp_state() == GraspState.HOLDING
    c = wsgemu.control
    c.pause()
    c.part(None)
    c.step(200)
    assert g.grasp_state() == GraspState.PART_LOST
    assert g.grasp_stats().lost_part == 1


def test_fast_stop_refuses_motion_until_acknowledged(wsgemu):
    g = _homed(wsgemu)
    c = wsgemu.control
    # Paused: no model step runs, and each answer shows its command's
    # effect all the same.
    c.pause()
    g.fast_stop()
    assert g.system_state() & SystemFlag.SF_FAST_STOP
    assert g.grasp_state() == GraspState.ERROR
    with pytest.raises(WsgError) as e:
        g.move(50.0, 100.0)
    assert e.value.status_name == "E_ACCESS_DENIED"
    with pytest.raises(WsgError) as e:
        g.home()
    assert e.value.status_name == "E_ACCESS_DENIED"
    g.ack()
    assert not g.system_state() & SystemFlag.SF_FAST_STOP
    assert g.grasp_state() == GraspState.IDLE
    # A motion right after "ack" is accepted, still without a step.
    pending = g.move(50.0, 100.0, wait=False)
    assert g.system_state() & SystemFlag.SF_MOVING
    c.resume()
    pending.wait()
    assert g.width() == pytest.approx(50.0, abs=0.01)


def test_ack_with_nothing_to_acknowledge_succeeds(wsgemu):
    # NOTES: drivers send ack with no fault pending and expect E_SUCCESS.
    wsgemu.gripper.ack()
    assert not wsgemu.gripper.system_state() & SystemFlag.SF_FAST_STOP


def test_paused_time_moves_only_when_stepped(wsgemu):
    g = wsgemu.gripper
    c = wsgemu.control
    assert c.pause() == "paused"
    t0 = c.time()
    time.sleep(0.2)
    assert c.time() == t0  # paused: no simulated time passes
    pending = g.home(wait=False)  # accepted: E_CMD_PENDING
    assert c.step(250) == pytest.approx(t0 + 0.25, abs=1e-6)
    assert not pending.done()
    w = g.width()
    assert 55.0 < w < STROKE  # on its way out, not there yet
    assert g.system_state() & SystemFlag.SF_MOVING
    # Homing from any position ends well within 4 s (NOTES).
    for _ in range(375):
        c.step(10)
        if pending.done():
            break
    assert pending.done()
    assert pending.wait().status == Status.E_SUCCESS
    assert g.width() == pytest.approx(STROKE, abs=0.01)
    assert c.time() < t0 + 4.0
    c.resume()
    t1 = c.time()
    time.sleep(0.2)
    assert c.time() > t1


def test_final_results_are_kept_until_waited_for(wsgemu):
    g = _homed(wsgemu)
    c = wsgemu.control
    c.pause()
    first = g.move(70.0, 100.0, wait=False)
    c.step(2000)  # the move ends; its final result is sent
    # Other commands read the final result off the wire before wait() does.
    assert g.width() == pytest.approx(70.0, abs=0.01)
    assert first.done()
    second = g.move(30.0, 100.0, wait=False)  # the same ID again
    assert not second.done()
    c.step(2000)
    assert g.grasp_state() == GraspState.IDLE
    assert first.wait().status == Status.E_SUCCESS
    assert second.wait().status == Status.E_SUCCESS
    assert g.width() == pytest.approx(30.0, abs=0.01)


def test_motion_final_result_times_out_while_paused(wsgemu):
    g = wsgemu.gripper
    wsgemu.control.pause()
    pending = g.home(wait=False)
    with pytest.raises(WsgTimeout):
        pending.wait(timeout=0.3)


def test_stop_aborts_a_running_motion(wsgemu):
    g = _homed(wsgemu)
    c = wsgemu.control
    c.pause()
    pending = g.move(10.0, 50.0, wait=False)
    c.step(100)
    g.stop()
    with pytest.raises(WsgError) as e:
        pending.wait()
    assert e.value.status_name == "E_CMD_ABORTED"
    assert g.system_state() & SystemFlag.SF_AXIS_STOPPED


def test_a_second_motion_while_moving_is_already_running(wsgemu):
    # NOTES: motion commands that arrive while moving get
    # E_ALREADY_RUNNING. The first client owes itself a final result, so
    # the second motion comes from another client.
    g = _homed(wsgemu)
    c = wsgemu.control
    c.pause()
    pending = g.move(20.0, 50.0, wait=False)
    c.step(50)
    with pytest.raises(WsgError) as e:
        wsgemu.new_gripper().move(80.0, 50.0)
    assert e.value.status_name == "E_ALREADY_RUNNING"
    # The same client refuses to send it: the answer could not be told
    # from the final result it is owed.
    with pytest.raises(RuntimeError):
        g.move(80.0, 50.0)
    c.resume()
    assert pending.wait().status == Status.E_SUCCESS
    assert g.width() == pytest.approx(20.0, abs=0.01)


def test_settings_are_clamped_to_the_models_limits(wsgemu):
    g = wsgemu.gripper
    assert g.get_acceleration() == pytest.approx(150.0)
    assert g.set_acceleration(10000.0) == pytest.approx(5000.0)
    assert g.set_acceleration(1.0) == pytest.approx(100.0)
    assert g.get_force_limit() == pytest.approx(40.0)
    assert g.set_force_limit(200.0) == pytest.approx(80.0)  # nominal
    g.overdrive(True)
    assert g.system_state() & SystemFlag.SF_OVERDRIVE_MODE
    assert g.set_force_limit(200.0) == pytest.approx(120.0)  # overdrive
    g.overdrive(False)
    # Leaving overdrive brings a limit above nominal back to nominal.
    assert g.get_force_limit() == pytest.approx(80.0)


def test_soft_limits_refuse_targets_outside(wsgemu):
    g = _homed(wsgemu)
    assert g.get_soft_limits() is None  # none set: E_NOT_AVAILABLE
    g.move(50.0, 100.0)
    g.set_soft_limits(20.0, 90.0)
    assert g.get_soft_limits() == pytest.approx((20.0, 90.0))
    with pytest.raises(WsgError) as e:
        g.move(100.0, 100.0)
    assert e.value.status_name == "E_RANGE_ERROR"
    g.clear_soft_limits()
    assert g.get_soft_limits() is None
    g.move(100.0, 100.0)
    assert g.width() == pytest.approx(100.0, abs=0.01)


def test_information_commands(wsgemu):
    g = wsgemu.gripper
    info = g.system_info()
    assert (info.type, info.type_name) == (1, "WSG 50")
    assert info.firmware == "2.2.0"
    assert info.serial_number == 1
    assert tuple(g.limits()) == pytest.approx(
        (110.0, 5.0, 420.0, 100.0, 5000.0, 5.0, 80.0, 120.0))
    assert g.temperature() == pytest.approx(25.0)
    assert g.tag() is None
    g.set_tag("cell 4")
    assert g.tag() == "cell 4"
    assert g.loop(b"\x00hello\xff") == b"\x00hello\xff"
    with pytest.raises(WsgError) as e:
        g.tare()  # no force measurement fingers
    assert e.value.status_name == "E_NOT_AVAILABLE"


@pytest.mark.wsgemu_args("--model", "wsg32", "--serial", "7",
                         "--tag", "cell 5")
def test_marker_arguments_reach_the_daemon(wsgemu):
    g = wsgemu.gripper
    info = g.system_info()
    assert (info.type, info.type_name, info.serial_number) == (2, "WSG 32", 7)
    assert g.limits().stroke == pytest.approx(68.0)
    assert g.limits().overdrive_force == pytest.approx(75.0)
    assert g.tag() == "cell 5"


def test_replies_are_found_among_auto_update_packets(wsgemu):
    g = _homed(wsgemu)
    # Subscribe to the width every 10 ms (FLAGS D0, PERIOD u16): its
    # packets (43h) then arrive mixed with the answers to other commands.
    r = g.request(Cmd.GET_WIDTH, struct.pack("<BH", 1, 10))
    assert r.status == Status.E_SUCCESS
    time.sleep(0.1)
    g.move(80.0, 200.0)
    for _ in range(5):
        assert g.system_state() & SystemFlag.SF_REFERENCED
        assert g.get_acceleration() == pytest.approx(150.0)
    assert g.request(Cmd.GET_WIDTH, struct.pack("<BH", 0, 0)).status == 0


def test_close_announces_the_disconnect(wsgemu, time_scale):
    c = wsgemu.control
    with wsgemu.new_gripper() as g:
        g.home()
    # close() sent 07h: no FAST STOP.
    assert not c.state()["flags"] & SystemFlag.SF_FAST_STOP
    # A client that just closes its socket puts the gripper into FAST STOP.
    s = socket.create_connection(wsgemu.tcp_addr)
    s.close()
    deadline = time.monotonic() + 5 * time_scale
    while not c.state()["flags"] & SystemFlag.SF_FAST_STOP:
        assert time.monotonic() < deadline, "no FAST STOP after a bare close"
        time.sleep(0.01)
    assert "fast_stop" in c.state()["flag_names"]


def test_after_disconnect_commands_are_refused(wsgemu):
    g = wsgemu.new_gripper()
    g.disconnect()
    with pytest.raises(WsgError) as e:
        g.width()
    assert e.value.status_name == "E_ACCESS_DENIED"


def test_control_drop_closes_the_connection(wsgemu):
    g = wsgemu.gripper
    assert wsgemu.control.drop().startswith("dropped 1")
    with pytest.raises((ConnectionError, OSError)):
        for _ in range(10):
            g.width()
            time.sleep(0.01)
    # A fresh client sees the FAST STOP the drop caused, and clears it.
    g2 = wsgemu.new_gripper()
    assert g2.system_state() & SystemFlag.SF_FAST_STOP
    g2.ack()
    time.sleep(0.05)
    assert not g2.system_state() & SystemFlag.SF_FAST_STOP


def test_control_errors_raise(wsgemu):
    with pytest.raises(ControlError) as e:
        wsgemu.control.command("bogus")
    assert "unknown command" in e.value.reason
    with pytest.raises(ControlError):
        wsgemu.control.fault("no-such-fault")


def test_control_fault_sets_its_flag(wsgemu):
    c = wsgemu.control
    c.fault("temp-warning", True)
    assert wsgemu.gripper.system_state() & SystemFlag.SF_TEMP_WARNING
    c.fault("temp-warning", False)
    assert not wsgemu.gripper.system_state() & SystemFlag.SF_TEMP_WARNING


def test_reset_forgets_the_reference(wsgemu):
    g = _homed(wsgemu)
    g.set_acceleration(300.0)
    assert wsgemu.control.reset() == "reset"
    assert not g.system_state() & SystemFlag.SF_REFERENCED
    assert g.get_acceleration() == pytest.approx(150.0)


def test_udp_client(wsgemu_binary):
    # The answer port must be known before the daemon starts: take a free
    # one from the kernel.
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        answer_port = s.getsockname()[1]
    from wsgemu import Emulator
    with Emulator(wsgemu_binary, ["--udp", "127.0.0.1:0:%d" % answer_port,
                                   "--time-scale", "10"]
                  ) as emu:
        assert emu.udp[0][2] == answer_port
        g = emu.new_udp_gripper()
        assert g.width() == pytest.approx(55.0)
        g.home()
        assert g.width() == pytest.approx(STROKE, abs=0.01)
        assert emu.gripper.system_state() & SystemFlag.SF_REFERENCED


# ---- the fingers (docs/fingers.md) ----

@pytest.mark.wsgemu_fingers("dsa", "fmf")
def test_finger_helpers_follow_a_grasp(wsgemu):
    g, c = wsgemu.gripper, wsgemu.control
    assert g.finger_info(0) == (3, 168) and g.finger_info(1) == (2, 4)
    assert g.finger_flags(0) & 0x3 == 0x3  # powered, data
    assert FingerFlag.POWERED in g.finger_flags(1)
    g.home()
    c.part(40.0)
    g.set_force_limit(20.0)
    g.grasp(40.0, 50.0)
    cells = g.finger_cells(0)
    assert len(cells) == 84 and max(cells) > 0
    assert cells == c.finger_cells(0)
    # The FMF finger reads the force held, as the channel says.
    assert g.finger_force(1) == pytest.approx(
        c.fingers()[1]["force"], abs=1e-3)
    assert g.finger_force(1) > 0
    g.finger_power(1, False)
    with pytest.raises(WsgError) as e:
        g.finger_data(1)
    assert e.value.status_name == "E_NOT_AVAILABLE"
    c.finger(1, "none")
    assert g.finger_info(1) == (0, 0)
    with pytest.raises(ValueError):
        g.finger_info(2)


# ---- the MuJoCo plant (docs/plants.md) ----

def test_object_and_pull_with_physics(wsgemu_binary):
    from wsgemu import DaemonError, Emulator
    emu = Emulator(wsgemu_binary, ["--physics", "mujoco"])
    try:
        emu.start()
    except DaemonError:
        # The wheel's static program and builds without libmujoco-dev
        # refuse --physics mujoco, saying so.
        if "MuJoCo" in emu.stderr_text():
            pytest.skip("this wsgemu has no MuJoCo plant")
        raise
    try:
        g, c = emu.gripper, emu.control
        c.pause()
        home = g.home(wait=False)
        c.step(2000)
        home.wait()
        assert c.object("box", 40, 20, 30, mass=0.1, friction=1) == \
            "object box 40 20 30 0.1 1"
        assert c.state()["object"]["kind"] == "box"
        grasp = g.grasp(40.0, 100.0, wait=False)
        c.step(2000)
        grasp.wait()
        assert g.grasp_state() == GraspState.HOLDING
        assert g.width() == pytest.approx(40.0, abs=0.5)  # docs/plants.md
        # Pulled harder than friction holds it: the part slips out.
        c.pull(500)
        c.step(500)
        assert g.grasp_state() == GraspState.PART_LOST
        c.object(None)
        assert c.state()["object"] is None
        with pytest.raises(ValueError):
            c.object("box", 40, 20, 30, friction=1)
    finally:
        emu.stop()
    with Emulator(wsgemu_binary) as builtin:
        with pytest.raises(ControlError):
            builtin.control.object("sphere", 30)
