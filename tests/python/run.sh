#!/bin/bash
# run.sh: the Python package's tests against a build's daemon. Makes a venv
# with Debian's python3 that sees the system's pytest (python3-pytest) and
# build backend (python3-setuptools, python3-wheel), runs `pip install
# --no-build-isolation PYDIR` into it, as python/README.md tells a user to,
# and runs PYDIR/tests with the daemon given. pip needs no package index:
# without build isolation it builds with Debian's setuptools instead of
# downloading one. Debian's /usr/bin/python3, not the first python3 on PATH:
# that may be another installation (pyenv's) without the system's packages.
#
# Usage: run.sh WSGEMU PYDIR VENV [PYTEST_ARGS...]
# Environment: WSG_TEST_TIME_SCALE (a number >= 1) multiplies the tests'
#   waits, as in the C tests (tests/integration/emu.h).
# Exit status: pytest's (0 all passed), 1 a setup step failed, 77 no
#   Debian python3 with venv and pytest here (scripts/deps.sh --test installs them).
set -u

if [ $# -lt 3 ]; then
    echo "usage: run.sh WSGEMU PYDIR VENV [PYTEST_ARGS...]" >&2
    exit 1
fi
wsgemu=$1
pydir=$2
venv=$3
shift 3

. "$(dirname "$0")/../need_python.sh"
need_python run.sh \
    "python3-venv python3-pytest python3-setuptools python3-wheel" \
    venv ensurepip pytest setuptools wheel

# Nothing written into the source tree: no bytecode caches, no
# .pytest_cache.
export PYTHONDONTWRITEBYTECODE=1
# Never ask, never reach for an index, and not wait on one either.
export PIP_NO_INPUT=1 PIP_DISABLE_PIP_VERSION_CHECK=1

# A new venv each run: what is tested is a fresh install of these sources.
if ! "$py" -m venv --clear --system-site-packages "$venv"; then
    echo "run.sh: cannot make the venv $venv" >&2
    exit 1
fi
# setuptools builds in the directory it is given (build/, *.egg-info):
# build from a copy in the build tree, so nothing is written into the
# sources.
src=$venv/src
mkdir -p "$src" && rm -rf "$src/wsgemu" &&
    cp -R "$pydir/pyproject.toml" "$pydir/README.md" "$pydir/wsgemu" "$src/" ||
    { echo "run.sh: cannot copy $pydir to $src" >&2; exit 1; }
if ! "$venv/bin/python" -m pip install --no-index --no-build-isolation \
        --quiet "$src"; then
    echo "run.sh: pip install $pydir failed" >&2
    exit 1
fi

# The fixture's wait for the ready line (10 s by default) is a bound like
# the C tests' waits: as long again as WSG_TEST_TIME_SCALE says.
ready_s=$(awk -v k="${WSG_TEST_TIME_SCALE:-1}" 'BEGIN { printf "%g", 10 * k }')

# The tests import the installed package: run from outside the source
# tree, so python/ itself is not on sys.path. --wsgemu=PATH in one word,
# or pytest would take the binary for a path to test.
cd "$venv" || exit 1
exec "$venv/bin/python" -m pytest -p no:cacheprovider -q -rs \
    -o "wsgemu_ready_timeout=$ready_s" \
    --rootdir "$pydir/tests" "--wsgemu=$wsgemu" "$@" "$pydir/tests"
