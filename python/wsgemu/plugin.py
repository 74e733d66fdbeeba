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
variable, else ``wsgemu`` on PATH. (One word with "=": pytest picks its
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
"""

import os

import pytest

from .client import ControlError
from .daemon import DaemonError, Emulator, find_binary


def pytest_addoption(parser):
    group = parser.getgroup("wsgemu", "wsgemu gripper emulator")
    group.addoption("--wsgemu", dest="wsgemu_binary", metavar="PATH",
                    default=None,
                    help="the wsgemu daemon the wsgemu fixture runs "
                         "(default: $WSGEMU, else wsgemu on PATH)")
    group.addoption("--wsgemu-script", dest="wsgemu_script", metavar="PATH",
                    default=None,
                    help="a Lua script every wsgemu daemon runs from its "
                         "start (--script); the wsgemu_script marker "
                         "overrides it")
    parser.addini("wsgemu_args", type="args", default=[],
                  help="extra arguments for every daemon the wsgemu "
                       "fixture starts")
    parser.addini("wsgemu_ready_timeout", default="10",
                  help="seconds the wsgemu fixture waits for the ready line")


def pytest_configure(config):
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


def daemon_args(node):
    """The extra arguments for node's daemon: the ini option's, then the
    markers' from the outermost (module, class) to the test itself."""
    args = list(node.config.getini("wsgemu_args"))
    for marker in reversed(list(node.iter_markers("wsgemu_args"))):
        # Each marker argument is one daemon argument, as given: a tag
        # "cell 5" stays one.
        args.extend(str(a) for a in marker.args)
    return args


def daemon_script(node):
    """The startup script for node's daemon: the nearest wsgemu_script
    marker's (a relative path taken from the directory of the test's
    file), else --wsgemu-script, else None."""
    marker = node.get_closest_marker("wsgemu_script")
    if marker is None:
        return node.config.getoption("wsgemu_script")
    if len(marker.args) != 1 or marker.kwargs:
        raise DaemonError("wsgemu_script takes one path (or None), not %r"
                          % (marker.args,))
    path = marker.args[0]
    if path is None:
        return None
    # node.path from pytest 7 on; fspath before (and deprecated since).
    where = getattr(node, "path", None) or node.fspath
    return os.path.join(os.path.dirname(str(where)), os.fspath(path))


def _script_failure(emu):
    """The error of a startup script that failed as it started, or None.
    Without it the test would see only E_CMD_UNKNOWN for the script's IDs;
    the script's own error says what is wrong."""
    if emu.script is None or emu.control_addr is None:
        return None
    status = emu.control.script_status()
    if status["running"] or not status["failed"]:
        return None
    return "the startup script %s failed: %s" % (emu.script, status["error"])


@pytest.fixture
def wsgemu(request):
    """A wsgemu daemon for this test, stopped (and its exit status 0
    checked) at teardown. See the module's documentation."""
    config = request.config
    failure = None
    emu = None
    try:
        binary = find_binary(config.getoption("wsgemu_binary"))
        emu = Emulator(binary, daemon_args(request.node),
                       ready_timeout=float(
                           config.getini("wsgemu_ready_timeout")),
                       script=daemon_script(request.node))
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
    if failure is not None:
        pytest.fail(failure, pytrace=False)
    try:
        yield emu
    finally:
        try:
            emu.stop()
        except DaemonError as e:
            failure = str(e)
        if failure is not None:
            pytest.fail(failure, pytrace=False)
