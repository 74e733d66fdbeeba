"""pytest plugin: the ``wsgemu`` fixture, a fresh emulated gripper per test.

Installed with the package, it is loaded through the ``pytest11`` entry
point: any test can ask for ``wsgemu`` without a conftest. The fixture runs
the daemon on free loopback ports (``--tcp 127.0.0.1:0 --control
127.0.0.1:0``), waits for its ready line, and yields a
``wsgemu.daemon.Emulator``:

- ``wsgemu.gripper``: a connected ``Gripper`` (TCP), ``wsgemu.control``: a
  connected ``Control``; ``new_gripper()``, ``new_control()`` and
  ``new_udp_gripper()`` connect more;
- ``tcp_addr``, ``control_addr``, ``tcp``, ``udp``, ``ready_line``,
  ``fields``, ``process``.

At teardown every client is closed (grippers with 07h), the daemon gets
SIGTERM, and the test errors unless it exits 0: a crash or a sanitizer
finding in the daemon does not go unnoticed.

Which daemon: ``pytest --wsgemu=PATH``, else the ``WSGEMU`` environment
variable, else the one bundled in the platform wheel, else ``wsgemu`` on
PATH. (One word with "=": pytest picks its
rootdir before it knows this option, and would take a separate PATH for a
path to test.) Extra daemon arguments: the ini option
``wsgemu_args`` (for every test), then those of ``wsgemu_args`` markers
(class, then function), e.g. ``@pytest.mark.wsgemu_args("--model",
"wsg32")``. ``wsgemu_ready_timeout`` (ini, seconds, default 10) bounds the
wait for the ready line.

A Lua script on the gripper from the start (the daemon's ``--script``):
``pytest --wsgemu-script=PATH`` for every test (PATH relative to where
pytest was started), or the ``wsgemu_script`` marker for a module, class
or test, the nearest one winning, e.g.
``@pytest.mark.wsgemu_script("scripts/pd.lua")`` (a relative path is
relative to the directory of the test's file); ``wsgemu_script(None)``
runs none. The fixture's ``script`` is the absolute path, or None. A
script that fails as it starts fails the test's setup with its error (to
test such a script, run it with ``control.script_run``).

The daemon keeps a communication log (``--log`` to a temporary file); when
a test that uses the fixture fails, its report gets two sections, the
daemon's stderr and the log's last lines, as fixtures of databases and
containers show theirs. It also captures every interface's traffic
(``--capture``); a failing test's capture is kept, as
``DIR/<test>.pcapng`` with DIR from ``--wsgemu-captures=DIR`` (else
``wsgemu-captures`` in the system's temporary directory), and its report
names the file, which Wireshark opens (the dissector wsg.lua decodes it).
``@pytest.mark.wsgemu_udp`` adds UDP on a free port answering to another
free port. ``@pytest.mark.wsgemu_fingers("dsa", "fmf")`` (or
``--wsgemu-fingers dsa,fmf`` for every test) fits the fingers
(``--finger0``, ``--finger1``; an attached daemon through its control
channel).

``wsgemu_session``: one daemon for the whole session (ini arguments and
``--wsgemu-script`` only; the markers are per test and do not apply).

Attach mode, ``pytest --wsgemu-attach=HOST:PORT[,control=HOST:PORT]`` or
the ``WSGEMU_ATTACH`` environment variable: no daemon is started, both
fixtures give an ``AttachedEmulator`` with the same clients for the one
that runs there (a CI service container); with a control address, each
``wsgemu`` test starts with ``control.reset()``. A test that needs a daemon
of its own (``wsgemu_args``, ``wsgemu_script`` or ``wsgemu_udp`` markers)
is skipped, saying why.
"""

import os
import re
import tempfile
from typing import Any, Generator, List, Optional, Union

import pytest

from .client import ControlError
from .daemon import AttachedEmulator, DaemonError, Emulator, find_binary

AnyEmulator = Union[Emulator, AttachedEmulator]

# A failing test's report shows this many of the log's last lines: what
# led up to the failure, without burying it under a long test's traffic.
LOG_LINES = 200

# The fixture names whose daemons a failing test's report shows.
_FIXTURES = ("wsgemu", "wsgemu_session")

# The markers that ask for a daemon of the test's own.
_OWN_DAEMON_MARKERS = ("wsgemu_args", "wsgemu_script", "wsgemu_udp")


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("wsgemu", "wsgemu gripper emulator")
    group.addoption("--wsgemu", dest="wsgemu_binary", metavar="PATH",
                    default=None,
                    help="the wsgemu daemon the wsgemu fixture runs "
                         "(default: $WSGEMU, else the bundled one, else "
                         "wsgemu on PATH)")
    group.addoption("--wsgemu-script", dest="wsgemu_script", metavar="PATH",
                    default=None,
                    help="a Lua script every wsgemu daemon runs from its "
                         "start (--script); the wsgemu_script marker "
                         "overrides it")
    group.addoption("--wsgemu-attach", dest="wsgemu_attach",
                    metavar="HOST:PORT[,control=HOST:PORT]", default=None,
                    help="start no daemon: the fixtures use the one running "
                         "there (default: $WSGEMU_ATTACH)")
    group.addoption("--wsgemu-captures", dest="wsgemu_captures",
                    metavar="DIR", default=None,
                    help="where a failing test's capture of the daemon's "
                         "traffic (pcapng) is kept (default: "
                         "wsgemu-captures in the temporary directory)")
    group.addoption("--wsgemu-fingers", dest="wsgemu_fingers",
                    metavar="KIND0[,KIND1]", default=None,
                    help="the fingers every wsgemu daemon is fitted with "
                         "(none, generic, fmf, dsa, device:FILE; "
                         "docs/fingers.md); the wsgemu_fingers marker "
                         "overrides it")
    parser.addini("wsgemu_args", type="args", default=[],
                  help="extra arguments for every daemon the wsgemu "
                       "fixture starts")
    parser.addini("wsgemu_ready_timeout", default="10",
                  help="seconds the wsgemu fixture waits for the ready line")


def pytest_configure(config: pytest.Config) -> None:
    # A relative --wsgemu is relative to where pytest was started, even
    # for a test that changes directory.
    if config.getoption("wsgemu_binary"):
        config.option.wsgemu_binary = os.path.abspath(
            config.getoption("wsgemu_binary"))
    if config.getoption("wsgemu_script"):
        config.option.wsgemu_script = os.path.abspath(
            config.getoption("wsgemu_script"))
    config.addinivalue_line(
        "markers",
        "wsgemu_args(*args): extra command-line arguments for this test's "
        "wsgemu daemon, e.g. wsgemu_args('--model', 'wsg32')")
    config.addinivalue_line(
        "markers",
        "wsgemu_script(path): the Lua script this test's wsgemu daemon runs "
        "from its start (--script), relative to the test file's directory; "
        "None: none")
    config.addinivalue_line(
        "markers",
        "wsgemu_fingers(kind0, kind1=None): the fingers this test's wsgemu "
        "daemon is fitted with (--finger0, --finger1), e.g. "
        "wsgemu_fingers('dsa', 'fmf')")
    config.addinivalue_line(
        "markers",
        "wsgemu_udp: this test's wsgemu daemon serves UDP too, on a free "
        "port, answering to a free port (new_udp_gripper())")


def _attach_spec(config: pytest.Config) -> Optional[str]:
    spec: Optional[str] = (config.getoption("wsgemu_attach")
                           or os.environ.get("WSGEMU_ATTACH") or None)
    return spec


def daemon_args(node: pytest.Item) -> List[str]:
    """The extra arguments for node's daemon: the ini option's, then the
    markers' from the outermost (module, class) to the test itself."""
    args = [str(a) for a in node.config.getini("wsgemu_args")]
    for marker in reversed(list(node.iter_markers("wsgemu_args"))):
        # Each marker argument is one daemon argument, as given: a tag
        # "cell 5" stays one.
        args.extend(str(a) for a in marker.args)
    for i, kind in enumerate(daemon_fingers(node)):
        if kind:
            args += ["--finger%d" % i, kind]
    return args


def daemon_fingers(node: pytest.Item) -> List[str]:
    """The kinds of node's daemon's fingers ("" for the default): the
    nearest wsgemu_fingers marker's, else --wsgemu-fingers."""
    marker = node.get_closest_marker("wsgemu_fingers")
    if marker is not None:
        kinds = [str(k) if k else "" for k in marker.args]
    else:
        opt = node.config.getoption("wsgemu_fingers")
        kinds = opt.split(",") if opt else []
    if len(kinds) > 2 or (marker is not None and marker.kwargs):
        raise DaemonError("wsgemu_fingers takes one or two kinds, not %r"
                          % (kinds,))
    return [k.strip() for k in kinds]


def daemon_script(node: pytest.Item) -> Optional[str]:
    """The startup script for node's daemon: the nearest wsgemu_script
    marker's (a relative path taken from the directory of the test's
    file), else --wsgemu-script, else None."""
    marker = node.get_closest_marker("wsgemu_script")
    if marker is None:
        script: Optional[str] = node.config.getoption("wsgemu_script")
        return script
    if len(marker.args) != 1 or marker.kwargs:
        raise DaemonError("wsgemu_script takes one path (or None), not %r"
                          % (marker.args,))
    path = marker.args[0]
    if path is None:
        return None
    return os.path.join(os.path.dirname(str(node.path)), os.fspath(path))


def _script_failure(emu: Emulator) -> Optional[str]:
    """The error of a startup script that failed as it started, or None.
    Without it the test would see only E_CMD_UNKNOWN for the script's IDs;
    the script's own error says what is wrong."""
    if emu.script is None or emu.control_addr is None:
        return None
    status = emu.control.script_status()
    if status["running"] or not status["failed"]:
        return None
    return "the startup script %s failed: %s" % (emu.script, status["error"])


def _start(config: pytest.Config, args: List[str], script: Optional[str],
           udp: bool) -> Emulator:
    """A started daemon, or the test fails with the daemon's error."""
    failure = None
    emu = None
    try:
        binary = find_binary(config.getoption("wsgemu_binary"))
        emu = Emulator(binary, args,
                       ready_timeout=float(
                           config.getini("wsgemu_ready_timeout")),
                       script=script, udp=udp, comm_log=True,
                       capture=True)
        emu.start()
        failure = _script_failure(emu)
    except (DaemonError, ControlError, OSError) as e:
        # OSError: the control channel failed (WsgTimeout is one too).
        failure = str(e)
    if failure is not None and emu is not None and emu.running:
        try:
            emu.stop()
        except DaemonError:
            pass
    # Failed outside the except block, so the report shows the daemon's
    # error once, not chained to the DaemonError.
    if failure is not None or emu is None:
        pytest.fail(failure or "no daemon", pytrace=False)
    return emu


def _stop(emu: AnyEmulator) -> None:
    """Stop the daemon (close the clients of an attached one); the test
    errors unless it exited 0."""
    try:
        emu.stop()
    except DaemonError as e:
        pytest.fail(str(e), pytrace=False)


@pytest.fixture
def wsgemu(request: pytest.FixtureRequest
           ) -> Generator[AnyEmulator, None, None]:
    """A wsgemu daemon for this test, stopped (and its exit status 0
    checked) at teardown. See the module's documentation."""
    node = request.node
    spec = _attach_spec(request.config)
    emu: AnyEmulator
    if spec is not None:
        own = [m for m in _OWN_DAEMON_MARKERS if node.get_closest_marker(m)]
        if own:
            pytest.skip("needs a daemon of its own (%s), but wsgemu is "
                        "attached to %s" % (", ".join(own), spec))
        emu = AttachedEmulator.from_spec(spec)
        if emu.control_addr is not None:
            # What a fresh daemon would be: the last test's state gone.
            emu.control.reset()
            for i, kind in enumerate(daemon_fingers(node)):
                if kind:
                    emu.control.finger(i, kind)
    else:
        emu = _start(request.config, daemon_args(node), daemon_script(node),
                     node.get_closest_marker("wsgemu_udp") is not None)
    try:
        yield emu
    finally:
        _stop(emu)


@pytest.fixture(scope="session")
def wsgemu_session(request: pytest.FixtureRequest
                   ) -> Generator[AnyEmulator, None, None]:
    """One wsgemu daemon for the whole session (ini wsgemu_args and
    --wsgemu-script; markers do not apply), stopped at its end. Tests
    that share it share the gripper's state."""
    config = request.config
    spec = _attach_spec(config)
    emu: AnyEmulator
    if spec is not None:
        emu = AttachedEmulator.from_spec(spec)
    else:
        emu = _start(config,
                     [str(a) for a in config.getini("wsgemu_args")],
                     config.getoption("wsgemu_script"), False)
    try:
        yield emu
    finally:
        _stop(emu)


def _capture_file(item: pytest.Item, fixture: str) -> Optional[str]:
    """Where a failing test's capture is kept: DIR/<test>[-<fixture>].pcapng,
    the test's node ID made a file name."""
    where = item.config.getoption("wsgemu_captures") or os.path.join(
        tempfile.gettempdir(), "wsgemu-captures")
    try:
        os.makedirs(where, exist_ok=True)
    except OSError:
        return None
    base = re.sub(r"[^A-Za-z0-9_.-]+", "_", item.nodeid).strip("_")[:180]
    if fixture != "wsgemu":
        base += "-" + fixture
    return os.path.join(where, base + ".pcapng")


# pytest's hookimpl is untyped (pytest 7): the ignore keeps --strict from
# taking the hook for untyped.
@pytest.hookimpl(hookwrapper=True)  # type: ignore[misc]
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]
                              ) -> Generator[None, Any, None]:
    """A failing test that used a daemon gets the daemon's stderr and the
    last LOG_LINES lines of its communication log in its report. Read
    now, while the daemon still runs: teardown comes after."""
    outcome = yield
    report: pytest.TestReport = outcome.get_result()
    if not report.failed:
        return
    funcargs = getattr(item, "funcargs", {})
    for name in _FIXTURES:
        emu = funcargs.get(name)
        if not isinstance(emu, (Emulator, AttachedEmulator)):
            continue
        stderr = emu.stderr_text()
        if stderr:
            report.sections.append(("%s: stderr" % name, stderr))
        log = emu.comm_log_text().splitlines()
        if log:
            shown = log[-LOG_LINES:]
            head = ("(the last %d of %d lines)\n" % (len(shown), len(log))
                    if len(shown) < len(log) else "")
            report.sections.append(("%s: communication log" % name,
                                    head + "\n".join(shown)))
        if isinstance(emu, Emulator) and emu.capture_path:
            path = _capture_file(item, name)
            size = emu.save_capture(path) if path else 0
            if size:
                report.sections.append((
                    "%s: capture" % name,
                    "%s (%d bytes of pcapng: wireshark -X "
                    "lua_script:wsg.lua %s, or with wsg.lua installed)"
                    % (path, size, path)))
