"""Shared pieces of the package's own tests.

The wsgemu fixture itself is not registered here: it comes from the
installed package's pytest11 entry point, as it does for any user, so these
tests also show that the plugin loads without a conftest. This file only
enables pytest's pytester (to run inner pytest sessions that exercise the
fixture's setup and teardown), names the daemon for tests that start one
by hand, and gives the factor of the tests' waits.
"""

import os

import pytest

from wsgemu import find_binary

pytest_plugins = ["pytester"]


@pytest.fixture
def wsgemu_binary(request):
    """The daemon the wsgemu fixture runs (--wsgemu, $WSGEMU or PATH)."""
    return find_binary(request.config.getoption("wsgemu_binary"))


@pytest.fixture
def time_scale():
    """The factor of the tests' own waits: $WSG_TEST_TIME_SCALE (a number
    >= 1, default 1), as for the C tests (tests/integration/emu.h). A wait
    is a bound on a hang, not an expectation: on a machine declared slower
    it is longer. tests/python/run.sh scales the fixture's ready timeout."""
    return max(1.0, float(os.environ.get("WSG_TEST_TIME_SCALE", "1")))
