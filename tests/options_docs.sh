#!/bin/sh
# options_docs.sh LIST SOURCE_DIR [WSGEMU]: every option of the daemon's
# settings table (LIST is options_list, which prints it) is in the man
# page's OPTIONS (a .TP tag), in the README's options table (its first
# column), and, if it is a config-file key (but a negation such as
# no-crc), in the example config (as "key = " or "#key = "); and none of
# the three names an option the table does not have. With WSGEMU, its
# --help too: every option, and each section heading once.
set -u
list=$1
src=$2
wsgemu=${3:-}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/wsgemu-options-docs.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
status=0

"$list" >"$tmp/table" || { echo "FAIL: $list failed"; exit 1; }
awk '{ print $1 }' "$tmp/table" | sort -u >"$tmp/all"
awk '$2 == "key" && $3 != "not" { print $1 }' "$tmp/table" |
    sort -u >"$tmp/keys"
[ -s "$tmp/all" ] || { echo "FAIL: the table is empty"; exit 1; }

# The man page: the tag line after each .TP of the OPTIONS section, with
# roff's \- read as -.
awk '/^\.SH / { on = ($0 == ".SH OPTIONS") } on && tag { print } \
     { tag = on && /^\.TP/ }' "$src/docs/man/wsgemu.1" |
    sed 's/\\-/-/g' | grep -o -- '--[a-z][a-z0-9-]*' | sed 's/^--//' |
    sort -u >"$tmp/man"

# The README: the first column of the table under "## Options", with \|
# (a | inside a cell) not taken for the end of the cell.
awk '/^#/ { on = ($0 == "## Options") } on && /^\| *`/' "$src/README.md" |
    sed 's/\\|/ /g' | awk -F'|' '{ print $2 }' |
    grep -o -- '--[a-z][a-z0-9-]*' | sed 's/^--//' | sort -u >"$tmp/readme"

# The example config: settings, active or commented out.
sed -n 's/^#\{0,1\}\([a-z][a-z0-9-]*\) = .*/\1/p' \
    "$src/packaging/wsgemu.conf" | sort -u >"$tmp/example"

# compare NAME WANT HAVE: what WANT lists and HAVE lacks, and the reverse.
compare() {
    missing=$(comm -23 "$2" "$3")
    extra=$(comm -13 "$2" "$3")
    if [ -n "$missing" ]; then
        echo "FAIL: $1 lacks:" $missing
        status=1
    fi
    if [ -n "$extra" ]; then
        echo "FAIL: $1 lists what is not a setting:" $extra
        status=1
    fi
    [ -n "$missing$extra" ] || echo "ok: $1: $(wc -l <"$3") settings"
}
# --help: the options at the start of its lines ("  --name", and the
# negations after a comma), and its headings (lines that start with a
# capital and end with a colon), none of them twice.
if [ -n "$wsgemu" ]; then
    "$wsgemu" --help >"$tmp/help.txt" || { echo "FAIL: $wsgemu --help"; exit 1; }
    grep -- '^  -' "$tmp/help.txt" | sed 's/^  //; s/  .*//' |
        grep -o -- '--[a-z][a-z0-9-]*' | sed 's/^--//' | sort -u >"$tmp/help"
    dup=$(grep '^[A-Z].*:$' "$tmp/help.txt" | sort | uniq -d)
    if [ -n "$dup" ]; then
        echo "FAIL: wsgemu --help repeats the heading(s): $dup"
        status=1
    fi
fi

compare "docs/man/wsgemu.1 OPTIONS" "$tmp/all" "$tmp/man"
compare "README.md's options table" "$tmp/all" "$tmp/readme"
compare "packaging/wsgemu.conf" "$tmp/keys" "$tmp/example"
[ -z "$wsgemu" ] || compare "wsgemu --help" "$tmp/all" "$tmp/help"
exit $status
