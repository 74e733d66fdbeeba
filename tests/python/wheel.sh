#!/bin/bash
# wheel.sh (test): the platform wheel gives the fixture and the emulator in
# one step. Builds it with scripts/wheel.sh and installs it with pip
# --no-index (nothing else) into a new venv of Debian's python3, the way
# python/README.md does: into a venv that has the package from ./python
# already (same version), with --force-reinstall, after which
# bundled_binary() must find both programs. Then a tiny pytest uses the
# wsgemu fixture with no WSGEMU set and no wsgemu on PATH: the daemon it
# runs must be the one inside the wheel. The venv sees the system's
# site-packages for pytest alone (Debian ships no pytest wheel to install
# offline); the test first checks that no wsgemu package is importable
# there, so only the install can provide it.
#
# Usage: wheel.sh SRC WORKDIR
# Exit status: 0 passed, 1 failed, 77 no Debian python3 with venv, pytest,
#   setuptools and wheel here (scripts/deps.sh --test installs them).
set -u

if [ $# -ne 2 ]; then
    echo "usage: wheel.sh SRC WORKDIR" >&2
    exit 1
fi
src=$1
work=$2
. "$(dirname "$0")/../need_python.sh"
# pip itself: scripts/wheel.sh runs Debian's (python3 -m pip wheel).
need_python wheel.sh \
    "python3-venv python3-pytest python3-setuptools python3-wheel python3-pip" \
    venv ensurepip pytest setuptools wheel pip
export PYTHONDONTWRITEBYTECODE=1 PIP_NO_INPUT=1 PIP_DISABLE_PIP_VERSION_CHECK=1

mkdir -p "$work" || exit 1
whl=$("$src/scripts/wheel.sh" --build-dir "$work/static" \
    --out "$work/dist" 2>"$work/build.log") ||
    { cat "$work/build.log" >&2; echo "wheel.sh: no wheel" >&2; exit 1; }
echo "wheel.sh: built $whl"

venv=$work/venv
"$py" -m venv --clear --system-site-packages "$venv" || exit 1
if "$venv/bin/python" -c "import wsgemu" 2>/dev/null; then
    echo "wheel.sh: a wsgemu package is importable before the install" >&2
    exit 1
fi
# As python/README.md goes: the package from the sources first (built from
# a copy: setuptools writes beside what it builds), then the wheel over it.
rm -rf "$work/pysrc" && mkdir -p "$work/pysrc" &&
    cp -R "$src/python/pyproject.toml" "$src/python/README.md" \
        "$src/python/wsgemu" "$work/pysrc/" || exit 1
"$venv/bin/python" -m pip install --quiet --no-index --no-build-isolation \
    "$work/pysrc" || exit 1
"$venv/bin/python" -m pip install --quiet --no-index --force-reinstall \
    "$whl" || exit 1
for prog in wsgemu wsgctl; do
    got=$("$venv/bin/python" -c "import wsgemu; print(wsgemu.bundled_binary('$prog'))")
    case $got in
    */wsgemu/bin/$prog) echo "wheel.sh: bundled_binary('$prog'): $got" ;;
    *)
        echo "wheel.sh: bundled_binary('$prog') is $got after the wheel's install" >&2
        exit 1
        ;;
    esac
done

tests=$work/tests
rm -rf "$tests" && mkdir -p "$tests"
cat > "$tests/test_one_step.py" <<'PY'
import os
import subprocess

import wsgemu as wsgemu_pkg  # the name wsgemu is the fixture's below


def test_the_fixture_runs_the_bundled_daemon(wsgemu):
    assert "WSGEMU" not in os.environ
    bundled = os.path.join(os.path.dirname(wsgemu_pkg.__file__), "bin")
    assert os.path.dirname(wsgemu.binary) == bundled
    assert wsgemu.gripper.loop(b"one step") == b"one step"


def test_wsgctl_is_bundled_too():
    wsgctl = wsgemu_pkg.bundled_binary("wsgctl")
    assert wsgctl is not None
    subprocess.run([wsgctl, "--help"], check=True, capture_output=True)

PY
# PATH: the venv's bin only, where no wsgemu is; WSGEMU unset.
if PATH="$venv/bin" command -v wsgemu >/dev/null; then
    echo "wheel.sh: a wsgemu on the test's PATH" >&2
    exit 1
fi
cd "$tests" || exit 1
exec env -u WSGEMU PATH="$venv/bin" "$venv/bin/python" -m pytest \
    -p no:cacheprovider -q "$tests"
