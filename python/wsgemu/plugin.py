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
"""

import os

import pytest

from .daemon import DaemonError, Emulator, find_binary


def pytest_addoption(parser):
    group = parser.getgroup("wsgemu", "wsgemu gripper emulator")
    group.addoption("--wsgemu", dest="wsgemu_binary", metavar="PATH",
                    default=None,
                    help="the wsgemu daemon the wsgemu fixture runs "
                         "(default: $WSGEMU, else wsgemu on PATH)")
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
    config.addinivalue_line(
        "markers",
        "wsgemu_args(*args): extra command-line arguments for this test's "
        "wsgemu daemon, e.g. wsgemu_args('--model', 'wsg32')")


def daemon_args(node):
    """The extra arguments for node's daemon: the ini option's, then the
    markers' from the outermost (module, class) to the test itself."""
    args = list(node.config.getini("wsgemu_args"))
    for marker in reversed(list(node.iter_markers("wsgemu_args"))):
        # Each marker argument is one daemon argument, as given: a tag
        # "cell 5" stays one.
        args.extend(str(a) for a in marker.args)
    return args


@pytest.fixture
def wsgemu(request):
    """A wsgemu daemon for this test, stopped (and its exit status 0
    checked) at teardown. See the module's documentation."""
    config = request.config
    failure = None
    try:
        binary = find_binary(config.getoption("wsgemu_binary"))
        emu = Emulator(binary, daemon_args(request.node),
                       ready_timeout=float(
                           config.getini("wsgemu_ready_timeout")))
        emu.start()
    except DaemonError as e:
        failure = str(e)
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
