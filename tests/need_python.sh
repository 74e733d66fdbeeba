# need_python.sh: sourced by the test scripts that run Debian's python3
# (tests/python/run.sh, tests/python/wheel.sh, tests/browser/run.sh).
# Debian's /usr/bin/python3, not the first python3 on PATH: that may be
# another installation (pyenv's) that cannot see Debian's packages.
#
# need_python WHO "PACKAGES" MODULE...: set py, or end the test as skipped
# (exit 77) when it or one of the modules is missing, saying which and what
# installs it.
py=/usr/bin/python3

need_python() {
    local who=$1 pkgs=$2 mod
    shift 2
    if [ ! -x "$py" ]; then
        echo "$who: skipped: no $py (scripts/deps.sh --test installs python3)"
        exit 77
    fi
    for mod in "$@"; do
        if ! "$py" -c "import $mod" 2>/dev/null; then
            echo "$who: skipped: $py has no module $mod" \
                 "(scripts/deps.sh --test installs $pkgs)"
            exit 77
        fi
    done
}
