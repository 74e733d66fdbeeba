"""The wsgemu fixture and the Emulator under it: the daemon's whole life
(started on free ports, ready line read, clients handed out, SIGTERM at
teardown with exit status 0 checked), the ways it can go wrong (no binary,
a daemon that exits at once, one that never gets ready, one that dies
during the test) and the marker and ini option that pass it arguments.
Inner pytest sessions (pytester) show what a user of the plugin sees; they
get the plugin from the installed package's entry point, like any user."""

import os
import re
import signal
import stat
import textwrap

import pytest

from wsgemu import Control, DaemonError, Emulator, Gripper, parse_ready_line

READY_RE = re.compile(
    r"^ready tcp=127\.0\.0\.1:(\d+) control=127\.0\.0\.1:(\d+)$")


def test_fixture_gives_a_running_daemon_and_clients(wsgemu):
    m = READY_RE.match(wsgemu.ready_line)
    assert m, wsgemu.ready_line
    tcp_port, control_port = int(m.group(1)), int(m.group(2))
    assert tcp_port > 0 and control_port > 0  # port 0 became a free port
    assert wsgemu.tcp_addr == ("127.0.0.1", tcp_port)
    assert wsgemu.control_addr == ("127.0.0.1", control_port)
    assert wsgemu.running
    assert isinstance(wsgemu.gripper, Gripper)
    assert wsgemu.gripper is wsgemu.gripper  # one client, connected once
    assert isinstance(wsgemu.control, Control)
    assert wsgemu.gripper.loop(b"ping") == b"ping"
    assert "width" in wsgemu.control.state()
    # More clients, each its own connection to the same gripper.
    other = wsgemu.new_gripper()
    assert other is not wsgemu.gripper
    wsgemu.gripper.set_acceleration(250.0)
    assert other.get_acceleration() == pytest.approx(250.0)
    assert wsgemu.new_control().time() >= 0.0


def test_ready_line_fields():
    f = parse_ready_line("ready tcp=127.0.0.1:5000,127.0.0.1:5001 "
                         "udp=127.0.0.1:6000>7000 control=127.0.0.1:2000")
    assert f == {"tcp": "127.0.0.1:5000,127.0.0.1:5001",
                 "udp": "127.0.0.1:6000>7000", "control": "127.0.0.1:2000"}
    with pytest.raises(DaemonError):
        parse_ready_line("wsgemu: something else")


def test_emulator_stops_with_sigterm_and_exit_status_0(wsgemu_binary):
    emu = Emulator(wsgemu_binary)
    emu.start()
    pid = emu.process.pid
    emu.gripper.home(wait=False)  # a motion still running at the stop
    assert emu.stop() == 0
    assert emu.process.returncode == 0
    assert not emu.running
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # reaped: gone


def test_emulator_reports_a_daemon_that_exits_at_once(wsgemu_binary):
    emu = Emulator(wsgemu_binary, ["--model", "no-such-model"])
    with pytest.raises(DaemonError) as e:
        emu.start()
    msg = str(e.value)
    assert "exited with status 2 before it was ready" in msg
    # The daemon's own message, from its stderr, is in the error.
    assert "no-such-model" in msg
    assert "--model no-such-model" in msg  # and the command line


def test_emulator_without_a_binary(monkeypatch, tmp_path):
    monkeypatch.delenv("WSGEMU", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))  # no wsgemu there
    with pytest.raises(DaemonError, match="no wsgemu binary"):
        Emulator()
    with pytest.raises(DaemonError, match="not an executable"):
        Emulator(str(tmp_path / "missing"))


def test_emulator_finds_the_binary_through_the_environment(
        monkeypatch, wsgemu_binary):
    monkeypatch.setenv("WSGEMU", wsgemu_binary)
    with Emulator() as emu:
        assert emu.binary == wsgemu_binary
        assert emu.gripper.system_info().firmware == "2.2.0"


def _script(tmp_path, body):
    path = tmp_path / "fake-wsgemu"
    path.write_text("#!/bin/sh\n" + body + "\n")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return str(path)


def test_emulator_times_out_on_a_daemon_that_never_gets_ready(tmp_path):
    fake = _script(tmp_path, "echo starting up >&2; exec sleep 30")
    emu = Emulator(fake, ready_timeout=0.5)
    with pytest.raises(DaemonError) as e:
        emu.start()
    assert "no ready line within 0.5 s" in str(e.value)
    assert "starting up" in str(e.value)
    assert emu.process.poll() is not None  # killed, not left behind


def test_emulator_reports_a_daemon_that_died_before_the_stop(wsgemu_binary):
    emu = Emulator(wsgemu_binary)
    emu.start()
    os.kill(emu.process.pid, signal.SIGKILL)
    emu.process.wait()
    with pytest.raises(DaemonError, match="had exited with status -9"):
        emu.stop()


# ---- the plugin as a user meets it: inner pytest sessions ----

def _run(pytester, wsgemu_binary, *args):
    # "--wsgemu=PATH" in one word: pytest takes a separate word that names
    # an existing file for a path to test, and would look for the inner
    # session's rootdir and ini file beside the binary.
    return pytester.runpytest("-p", "no:cacheprovider",
                              "--wsgemu=" + wsgemu_binary, *args)


def test_plugin_lifecycle_in_a_users_project(pytester, wsgemu_binary,
                                             tmp_path):
    pids = tmp_path / "pids"
    pytester.makepyfile(test_user=textwrap.dedent("""
        def test_one(wsgemu):
            with open(%r, "a") as f:
                f.write("%%d\\n" %% wsgemu.process.pid)
            wsgemu.gripper.home()
            assert wsgemu.gripper.width() > 100

        def test_two(wsgemu):
            with open(%r, "a") as f:
                f.write("%%d\\n" %% wsgemu.process.pid)
            assert not wsgemu.control.state()["flags"] & 1  # fresh gripper
    """ % (str(pids), str(pids))))
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(passed=2)
    started = [int(p) for p in pids.read_text().split()]
    assert len(set(started)) == 2  # one daemon per test
    for pid in started:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)  # stopped and reaped at teardown


def test_plugin_fails_clearly_when_the_daemon_cannot_start(pytester,
                                                           wsgemu_binary):
    pytester.makepyfile(test_user="""
        import pytest

        @pytest.mark.wsgemu_args("--acceleration", "99999")
        def test_bad(wsgemu):
            pass
    """)
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines([
        "*wsgemu exited with status 2 before it was ready*",
        "*--acceleration 99999*",
        "*stderr:*",
    ])
    # The daemon's own complaint is shown, not hidden.
    assert "acceleration" in "\n".join(
        result.stdout.lines[result.stdout.lines.index(next(
            line for line in result.stdout.lines if "stderr:" in line)):])


def test_plugin_reports_a_daemon_that_crashed_during_the_test(
        pytester, wsgemu_binary):
    pytester.makepyfile(test_user="""
        import os, signal

        def test_crash(wsgemu):
            os.kill(wsgemu.process.pid, signal.SIGABRT)
            wsgemu.process.wait()
    """)
    result = _run(pytester, wsgemu_binary)
    # The test body passed; the teardown's check of the exit status did not.
    result.assert_outcomes(passed=1, errors=1)
    result.stdout.fnmatch_lines(["*had exited with status -6*"])


def test_plugin_ini_option_and_markers_add_arguments(pytester,
                                                     wsgemu_binary):
    pytester.makeini("""
        [pytest]
        wsgemu_args = --serial 42 --model wsg25
    """)
    pytester.makepyfile(test_user="""
        import pytest

        pytestmark = pytest.mark.wsgemu_args("--tag", "outer tag")

        def test_ini(wsgemu):
            info = wsgemu.gripper.system_info()
            assert (info.type_name, info.serial_number) == ("WSG 25", 42)
            assert wsgemu.gripper.tag() == "outer tag"

        @pytest.mark.wsgemu_args("--tag", "inner")
        def test_marker_last_wins(wsgemu):
            # The test's own marker comes after the module's.
            assert wsgemu.gripper.tag() == "inner"
            assert "--tag inner" in " ".join(wsgemu.argv)
    """)
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(passed=2)


def test_plugin_without_a_binary_says_how_to_give_one(pytester,
                                                      monkeypatch):
    monkeypatch.delenv("WSGEMU", raising=False)
    monkeypatch.setenv("PATH", str(pytester.path))
    pytester.makepyfile(test_user="""
        def test_needs(wsgemu):
            pass
    """)
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*no wsgemu binary*--wsgemu=PATH*"])


def test_plugin_documents_its_options(pytester):
    result = pytester.runpytest("--help")
    result.stdout.fnmatch_lines(["*--wsgemu=PATH*", "*wsgemu_args*"])
    result = pytester.runpytest("--markers")
    result.stdout.fnmatch_lines(["*@pytest.mark.wsgemu_args(*args)*"])
