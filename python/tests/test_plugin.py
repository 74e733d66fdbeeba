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


# ---- the log in a failing test's report, the session fixture, attach
# mode, free UDP answer ports, and where the daemon is found ----

def test_a_failing_tests_report_shows_the_daemons_log(pytester,
                                                      wsgemu_binary):
    pytester.makepyfile(test_user="""
        def test_fails(wsgemu):
            assert wsgemu.gripper.width() < 0

        def test_passes(wsgemu):
            wsgemu.gripper.width()
    """)
    result = _run(pytester, wsgemu_binary, "-rA")
    result.assert_outcomes(failed=1, passed=1)
    out = result.stdout.str()
    # The failing test's report has the communication log with its
    # request (43h) ...
    result.stdout.fnmatch_lines([
        "*- wsgemu: communication log -*",
        "*tcp 127.0.0.1:* in 43h GetOpeningWidth",
        "*tcp 127.0.0.1:* out 43h GetOpeningWidth E_SUCCESS width=55.000"])
    # ... the passing one's none.
    assert out.count("communication log") == 1


def test_a_failing_tests_capture_is_kept_and_named(pytester, wsgemu_binary,
                                                  tmp_path):
    captures = tmp_path / "captures"
    pytester.makepyfile(test_user="""
        def test_fails(wsgemu):
            assert wsgemu.gripper.width() < 0

        def test_passes(wsgemu):
            wsgemu.gripper.width()
    """)
    result = _run(pytester, wsgemu_binary, "-rA",
                  "--wsgemu-captures=%s" % captures)
    result.assert_outcomes(failed=1, passed=1)
    result.stdout.fnmatch_lines(["*- wsgemu: capture -*",
                                 "*test_fails.pcapng (* bytes of pcapng*"])
    # Only the failing test's is kept: a pcapng file (its Section Header
    # Block) holding the request's bytes (43h: AA AA AA 43 00 00).
    kept = list(captures.iterdir())
    assert [k.name for k in kept] == ["test_user.py_test_fails.pcapng"]
    data = kept[0].read_bytes()
    assert data[:4] == b"\x0a\x0d\x0d\x0a"
    assert b"\xaa\xaa\xaa\x43\x00\x00" in data


def test_session_fixture_is_one_daemon_for_all_tests(pytester,
                                                     wsgemu_binary,
                                                     tmp_path):
    pids = tmp_path / "pids"
    pytester.makepyfile(test_user="""
        def test_one(wsgemu_session):
            open(%r, "a").write("%%d\\n" %% wsgemu_session.process.pid)
            wsgemu_session.gripper.set_acceleration(250.0)

        def test_two(wsgemu_session):
            open(%r, "a").write("%%d\\n" %% wsgemu_session.process.pid)
            # The state the first test left: the same daemon.
            assert round(wsgemu_session.gripper.get_acceleration()) == 250
    """ % (str(pids), str(pids)))
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(passed=2)
    [pid] = set(int(p) for p in pids.read_text().split())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # stopped at the session's end


@pytest.mark.parametrize("how", ["option", "environment"])
def test_attach_mode_uses_a_running_daemon(pytester, wsgemu_binary,
                                           monkeypatch, how):
    with Emulator(wsgemu_binary) as emu:
        emu.gripper.home()
        spec = "%s:%d,control=%s:%d" % (*emu.tcp_addr, *emu.control_addr)
        pytester.makepyfile(test_user="""
            import pytest

            def test_attached(wsgemu):
                assert wsgemu.process is None  # nothing started
                assert wsgemu.tcp_addr == (%r, %d)
                # control.reset() at the start: not homed any more.
                assert not wsgemu.control.state()["flags"] & 1
                assert wsgemu.gripper.loop(b"x") == b"x"

            def test_session(wsgemu_session):
                assert wsgemu_session.process is None

            @pytest.mark.wsgemu_args("--model", "wsg32")
            def test_needs_its_own(wsgemu):
                pass
        """ % emu.tcp_addr)
        if how == "option":
            result = pytester.runpytest("-p", "no:cacheprovider", "-rs",
                                        "--wsgemu-attach=" + spec)
        else:
            monkeypatch.setenv("WSGEMU_ATTACH", spec)
            result = pytester.runpytest("-p", "no:cacheprovider", "-rs")
        result.assert_outcomes(passed=2, skipped=1)
        result.stdout.fnmatch_lines(["*needs a daemon of its own "
                                     "(wsgemu_args)*attached to*"])
        assert emu.running  # left running: not the fixture's to stop
        assert emu.gripper.loop(b"y") == b"y"


def test_udp_marker_picks_free_answer_ports(pytester, wsgemu_binary):
    pytester.makepyfile(test_user="""
        import pytest
        from wsgemu import Emulator

        @pytest.mark.wsgemu_udp
        def test_udp(wsgemu, wsgemu_binary):
            [(host, port, answer)] = wsgemu.udp
            assert answer != 1501 and port != 1500
            assert wsgemu.new_udp_gripper().loop(b"u") == b"u"
            # A second daemon at the same time answers to another port.
            with Emulator(wsgemu_binary, udp=True) as other:
                assert other.udp[0][2] != answer
                assert other.new_udp_gripper().loop(b"v") == b"v"
    """)
    pytester.makeconftest("""
        import pytest
        from wsgemu import find_binary

        @pytest.fixture
        def wsgemu_binary(request):
            return find_binary(request.config.getoption("wsgemu_binary"))
    """)
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(passed=1)


def test_find_binary_order(monkeypatch, tmp_path, wsgemu_binary):
    import wsgemu.daemon as daemon
    bundled = tmp_path / "bin"
    bundled.mkdir()
    on_path = tmp_path / "path"
    on_path.mkdir()
    for d in (bundled, on_path):
        os.symlink(wsgemu_binary, str(d / "wsgemu"))
    monkeypatch.setattr(daemon, "BUNDLED_DIR", str(bundled))
    monkeypatch.setenv("PATH", str(on_path))
    monkeypatch.setenv("WSGEMU", wsgemu_binary)
    assert daemon.find_binary("/bin/true") == "/bin/true"  # given: first
    assert daemon.find_binary() == wsgemu_binary           # then $WSGEMU
    monkeypatch.delenv("WSGEMU")
    assert daemon.find_binary() == str(bundled / "wsgemu")  # then bundled
    monkeypatch.setattr(daemon, "BUNDLED_DIR", str(tmp_path / "none"))
    assert daemon.find_binary() == str(on_path / "wsgemu")  # then PATH


def test_fixture_fits_fingers(pytester, wsgemu_binary):
    pytester.makepyfile(test_user="""
        import pytest

        @pytest.mark.wsgemu_fingers("dsa", "fmf")
        def test_marker(wsgemu):
            g = wsgemu.gripper
            assert g.finger_info(0) == (3, 168)
            assert g.finger_info(1) == (2, 4)
            assert g.finger_cells(0) == [0] * 84
            assert g.finger_force(1) == 0.0

        def test_option(wsgemu):
            assert wsgemu.gripper.finger_info(0) == (0, 0)
            assert wsgemu.control.fingers()[1]["kind"] == "generic"
    """)
    result = _run(pytester, wsgemu_binary, "--wsgemu-fingers", "none")
    result.assert_outcomes(passed=2)
