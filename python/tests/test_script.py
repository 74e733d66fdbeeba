"""Scripts on the gripper through the package: Control's script_run,
script_stop, script_status and script_output (all of it in chunks, only
what is new, what the daemon's 64 KiB ring let go, bytes that are not
UTF-8), the errors a run can meet, Emulator(script=...), and the fixture's
wsgemu_script marker and --wsgemu-script option as a user meets them
(inner pytest sessions). The scripts are small ones written into tmp_path;
the driver-shaped test of a whole script is test_pd_driver.py."""

import os
import textwrap

import pytest

from wsgemu import (ControlError, DaemonError, Emulator, Status,
                    SystemFlag)

# A script that stays: registers an ID, answers it, prints what it does.
ECHO = """
cmd.register(0xB0)
print("echo ready")
while true do
  local id, payload = cmd.read()
  printf("got %d bytes\\n", #payload)
  cmd.send(id, etob(E_SUCCESS), payload)
end
"""


def _lua(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_run_status_and_stop(wsgemu, tmp_path):
    c, g = wsgemu.control, wsgemu.gripper
    path = _lua(tmp_path, "echo.lua", ECHO)
    before = c.script_status()
    assert (before["running"], before["file"], before["state"]) == (
        False, None, "stopped")
    assert c.script_run(path) == "script running %s" % path
    st = c.script_status()
    assert st["running"] and not st["failed"] and st["error"] is None
    assert st["file"] == str(path)
    assert st["state"] == "reading"  # waiting in cmd.read
    assert st["registered"] == [0xB0]
    assert 0 < st["memory"] <= st["memory_max"]
    assert g.system_state() & SystemFlag.SF_SCRIPT_RUNNING
    assert g.command(0xB0, b"\x01\x02") == b"\x01\x02"
    # One script at a time.
    with pytest.raises(ControlError) as e:
        c.script_run(path)
    assert "stop it first" in e.value.reason
    assert c.script_stop() is True
    assert c.script_stop() is False  # none was running
    st = c.script_status()
    assert (st["running"], st["failed"], st["registered"]) == (False, False,
                                                               [])
    assert not g.system_state() & SystemFlag.SF_SCRIPT_RUNNING
    # Its ID is unknown again.
    assert g.request(0xB0).status == Status.E_CMD_UNKNOWN


def test_a_relative_path_is_taken_from_the_clients_directory(
        wsgemu, tmp_path, monkeypatch):
    _lua(tmp_path, "echo.lua", ECHO)
    monkeypatch.chdir(tmp_path)
    assert wsgemu.control.script_run("echo.lua").endswith(
        " " + str(tmp_path / "echo.lua"))
    assert wsgemu.control.script_status()["file"] == str(
        tmp_path / "echo.lua")


def test_run_errors(wsgemu, tmp_path):
    c, g = wsgemu.control, wsgemu.gripper
    with pytest.raises(ControlError) as e:
        c.script_run(tmp_path / "missing.lua")
    assert e.value.reason == "script: %s: No such file or directory" % (
        tmp_path / "missing.lua")
    with pytest.raises(ValueError, match="blank"):
        c.script_run(tmp_path / "with space.lua")
    # A syntax error, and an error before the script's first wait: the
    # run fails with the message, the gripper shows SF_SCRIPT_FAILURE.
    for name, text, message in (
            ("syntax.lua", "x = = 1\n", "syntax.lua:1: unexpected symbol"),
            ("fails.lua", "error('no gripper here')\n",
             "fails.lua:1: no gripper here")):
        with pytest.raises(ControlError) as e:
            c.script_run(_lua(tmp_path, name, text))
        assert message in e.value.reason
        st = c.script_status()
        assert not st["running"] and st["failed"]
        assert message in st["error"]
        assert g.system_state() & SystemFlag.SF_SCRIPT_FAILURE
    # The error is in the output too, as on the gripper's console.
    assert "error: " in c.script_output()
    # A new run clears the failure.
    c.script_run(_lua(tmp_path, "echo.lua", ECHO))
    assert not g.system_state() & SystemFlag.SF_SCRIPT_FAILURE


def test_output_whole_and_new(wsgemu, tmp_path):
    c, g = wsgemu.control, wsgemu.gripper
    assert c.script_output() == "" and c.script_output_end == 0
    # More than one answer of the channel holds (about 1 KiB each), with
    # a character of two bytes that falls wherever it falls.
    lines = ["%03d °C %s" % (i, "x" * 30) for i in range(100)]
    c.script_run(_lua(tmp_path, "many.lua", "".join(
        "print(%r)\n" % line for line in lines) + ECHO))
    text = c.script_output()
    assert text == "\n".join(lines) + "\necho ready\n"
    assert c.script_output_end == len(text.encode("utf-8"))
    assert c.script_output_lost == 0
    assert c.script_output_new() == ""  # nothing since
    g.command(0xB0, b"abc")
    assert c.script_output_new() == "got 3 bytes\n"
    g.command(0xB0, b"")
    g.command(0xB0, b"x")
    assert c.script_output_new() == "got 0 bytes\ngot 1 bytes\n"
    # From any offset, and another client has its own offset.
    assert c.script_output(len(text.encode("utf-8"))).startswith(
        "got 3 bytes\n")
    other = wsgemu.new_control()
    assert other.script_output_new() == c.script_output()


def test_output_past_the_ring_is_counted_as_lost(wsgemu, tmp_path):
    c = wsgemu.control
    c.script_run(_lua(tmp_path, "flood.lua", """
        for i = 1, 80 do print(string.rep(string.char(64 + i % 26), 1023)) end
        print("last")
    """))
    text = c.script_output()
    printed = 80 * 1024 + 5
    assert len(text) == 65536  # the daemon keeps the last 64 KiB
    assert text.endswith("\nlast\n")
    assert c.script_output_lost == printed - 65536
    assert c.script_output_end == printed


def test_output_bytes_that_are_not_utf8(wsgemu, tmp_path):
    c = wsgemu.control
    with pytest.raises(ControlError) as e:
        c.script_run(_lua(tmp_path, "bytes.lua",
                          'print("a\\255b\\tc")\nerror("bad \\255")\n'))
    assert e.value.reason.endswith("bad \ufffd")
    assert c.script_output().startswith("a\ufffdb\tc\nerror: ")
    assert c.script_status()["error"].endswith("bad \ufffd")


def test_emulator_runs_a_startup_script(wsgemu_binary, tmp_path,
                                        monkeypatch):
    _lua(tmp_path, "echo.lua", ECHO)
    monkeypatch.chdir(tmp_path)
    with Emulator(wsgemu_binary, script="echo.lua") as emu:
        assert emu.script == str(tmp_path / "echo.lua")
        assert emu.argv[-2:] == ["--script", emu.script]
        # Registered before the ready line: the first packet finds it.
        assert emu.gripper.command(0xB0, b"hi") == b"hi"
        assert emu.control.script_output() == "echo ready\ngot 2 bytes\n"


def test_emulator_with_a_script_that_cannot_be_read(wsgemu_binary,
                                                    tmp_path):
    emu = Emulator(wsgemu_binary, script=tmp_path / "missing.lua")
    with pytest.raises(DaemonError) as e:
        emu.start()
    assert "missing.lua: No such file or directory" in str(e.value)


# ---- the marker and the option, as a user meets them ----

def _run(pytester, wsgemu_binary, *args):
    return pytester.runpytest("-p", "no:cacheprovider",
                              "--wsgemu=" + wsgemu_binary, *args)


def test_marker_and_option(pytester, wsgemu_binary):
    os.mkdir(pytester.path / "scripts")
    (pytester.path / "scripts" / "echo.lua").write_text(ECHO)
    (pytester.path / "other.lua").write_text(
        'cmd.register(0xB3)\nprint("other")\n'
        'while true do local id = cmd.read() cmd.send(id, etob(0)) end\n')
    pytester.makepyfile(test_user="""
        import pytest

        pytestmark = pytest.mark.wsgemu_script("scripts/echo.lua")

        def test_module_marker(wsgemu):
            assert wsgemu.script.endswith("/scripts/echo.lua")
            assert wsgemu.gripper.command(0xB0, b"x") == b"x"

        @pytest.mark.wsgemu_script("other.lua")
        def test_nearest_marker_wins(wsgemu):
            assert wsgemu.control.script_output() == "other\\n"

        @pytest.mark.wsgemu_script(None)
        def test_none(wsgemu):
            assert wsgemu.script is None
            assert not wsgemu.control.script_status()["running"]
    """)
    # Another directory: the marker's path is the test file's, not the
    # working directory's.
    os.mkdir(pytester.path / "elsewhere")
    os.chdir(pytester.path / "elsewhere")
    result = _run(pytester, wsgemu_binary, str(pytester.path))
    result.assert_outcomes(passed=3)
    # The option for tests without a marker (relative to where pytest
    # runs).
    os.chdir(pytester.path)
    pytester.makepyfile(test_user="""
        def test_option(wsgemu):
            assert wsgemu.control.script_output() == "other\\n"
    """)
    result = _run(pytester, wsgemu_binary, "--wsgemu-script=other.lua")
    result.assert_outcomes(passed=1)


def test_a_startup_script_that_fails_fails_the_setup(pytester,
                                                     wsgemu_binary):
    (pytester.path / "broken.lua").write_text("cmd.register(0xB0)\nx = = 1\n")
    pytester.makepyfile(test_user="""
        import pytest

        @pytest.mark.wsgemu_script("broken.lua")
        def test_never_runs(wsgemu):
            pass
    """)
    result = _run(pytester, wsgemu_binary)
    result.assert_outcomes(errors=1)
    # Outside a script directory the error names the line and Lua's
    # words, not the file's text.
    result.stdout.fnmatch_lines([
        "*the startup script */broken.lua failed: "
        "*broken.lua:2: unexpected symbol (*"])
    result.stdout.no_fnmatch_line("*near '='*")


def test_plugin_documents_the_script_option_and_marker(pytester):
    result = pytester.runpytest("--help")
    result.stdout.fnmatch_lines(["*--wsgemu-script=PATH*"])
    result = pytester.runpytest("--markers")
    result.stdout.fnmatch_lines(["*@pytest.mark.wsgemu_script(path)*"])
