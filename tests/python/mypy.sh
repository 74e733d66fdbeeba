#!/bin/sh
# mypy.sh: the Python package passes mypy --strict (its py.typed promises
# users annotations they can check against). Debian's mypy (python3-mypy);
# exit 77 where it is missing.
# Usage: mypy.sh PYDIR CACHEDIR
set -u
if ! /usr/bin/python3 -c "import mypy" 2>/dev/null; then
    echo "mypy.sh: skipped: no mypy (scripts/deps.sh --test installs python3-mypy)"
    exit 77
fi
cd "$1" || exit 1
exec /usr/bin/python3 -m mypy --strict --cache-dir "$2" wsgemu
