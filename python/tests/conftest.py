"""Shared pieces of the package's own tests.

The wsgemu fixture itself is not registered here: it comes from the
installed package's pytest11 entry point, as it does for any user, so these
tests also show that the plugin loads without a conftest. This file only
enables pytest's pytester (to run inner pytest sessions that exercise the
fixture's setup and teardown) and names the daemon for tests that start one
by hand.
"""

import pytest

from wsgemu import find_binary

pytest_plugins = ["pytester"]


@pytest.fixture
def wsgemu_binary(request):
    """The daemon the wsgemu fixture runs (--wsgemu, $WSGEMU or PATH)."""
    return find_binary(request.config.getoption("wsgemu_binary"))
