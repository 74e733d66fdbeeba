#!/bin/bash
# run.sh: the web page's tests in a real browser. Debian's Chromium runs
# headless, driven through WebDriver (chromium-driver) by Debian's
# python3-selenium from pytest; the daemon is started by the project's own
# Python package (python/, put on the path, not installed).
#
# Usage: run.sh WSGEMU SRCDIR ARTIFACTS [PYTEST_ARGS...]
#   ARTIFACTS: a directory for screenshots (web-page.png, and one per
#   failed test).
# Environment: WSG_TEST_TIME_SCALE (a number >= 1) multiplies the waits;
#   WSG_HAVE_WEB=0 (set by ctest for a build without libmicrohttpd) skips.
# Exit status: pytest's (0 all passed), 77 when Chromium, its driver or
#   selenium is missing (scripts/deps.sh --test installs them).
set -u

if [ $# -lt 3 ]; then
    echo "usage: run.sh WSGEMU SRCDIR ARTIFACTS [PYTEST_ARGS...]" >&2
    exit 1
fi
wsgemu=$1
src=$2
artifacts=$3
shift 3

for need in /usr/bin/chromium /usr/bin/chromedriver; do
    if [ ! -x "$need" ]; then
        echo "run.sh: skipped: no $need" \
             "(scripts/deps.sh --test installs chromium chromium-driver)"
        exit 77
    fi
done
. "$(dirname "$0")/../need_python.sh"
need_python run.sh "python3-pytest python3-selenium" pytest selenium
# A build without libmicrohttpd has no page to test (ctest says which).
if [ "${WSG_HAVE_WEB:-1}" != 1 ]; then
    echo "run.sh: skipped: wsgemu was built without libmicrohttpd"
    exit 77
fi

mkdir -p "$artifacts"
export WSG_BROWSER_ARTIFACTS=$artifacts
export WSGEMU=$wsgemu
export PYTHONPATH="$src/python${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONDONTWRITEBYTECODE=1
# Chromium wants a writable home for its profile; a fresh one per run.
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
export HOME=$home
cd "$src/tests/browser" || exit 1
"$py" -m pytest -p no:cacheprovider -q "$@" .
