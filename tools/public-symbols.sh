#!/bin/sh
# public-symbols.sh HEADER [--map]
#
# Prints the names of the functions HEADER (include/btfcar.h) declares, one a
# line, sorted: the public API, and so the export list of libbtfcar.so. With
# --map, prints them as a linker version script that exports those names and
# makes every other symbol local (the Makefile's $(BUILD)/gen/btfcar.map).
#
# HEADER is the umbrella header: its topical headers are the files of the
# folder beside it named like it (include/btfcar/*.h), and what they declare
# counts as HEADER's own.
#
# The names come from the header's declarations, not from a prefix (the
# library's internal helpers start with btf_ too): the header is run through
# the C preprocessor ($CC, default cc), only the lines that come from HEADER
# itself and from its topical headers are kept (not those of the system
# headers they include), and every identifier directly followed by "("
# outside all parentheses and braces, in a statement that is not a typedef,
# is a declared function.
#
# POSIX sh and awk only.
set -eu
hdr=${1:?usage: public-symbols.sh HEADER [--map]}
mode=${2:-}

# The topical headers' folder: include/btfcar.h -> include/btfcar/
topical="${hdr%.h}/"
pp=$(${CC:-cc} -E -x c "$hdr")

# A topical header the umbrella does not include would declare functions
# that are neither exported nor checked: refuse it.
for t in "$topical"*.h; do
    [ -e "$t" ] || continue
    if ! printf '%s\n' "$pp" | grep -q "^# [0-9]* \"$t\""; then
        echo "public-symbols.sh: $hdr does not include $t" >&2
        exit 1
    fi
done

names=$(printf '%s\n' "$pp" | awk -v want="$hdr" -v topical="$topical" '
    # Line markers: # LINE "FILE" FLAGS
    /^# [0-9]+ "/ {
        f = $3
        gsub(/"/, "", f)
        keep = (f == want || substr(f, 1, length(topical)) == topical)
        next
    }
    /^#/ { next }
    keep { text = text $0 "\n" }
    END {
        n = length(text)
        paren = 0; brace = 0
        id = ""; last = ""; first = ""
        for (i = 1; i <= n + 1; i++) {
            c = (i <= n) ? substr(text, i, 1) : ";"
            if (c ~ /[A-Za-z0-9_]/) {
                id = id c
                continue
            }
            if (id != "") {
                if (paren == 0 && brace == 0 && first == "")
                    first = id
                last = (id ~ /^[0-9]/) ? "" : id
                id = ""
            }
            if (c ~ /[ \t\n\r]/)
                continue
            if (c == "(") {
                if (paren == 0 && brace == 0 && first != "typedef" && last != "" &&
                    last !~ /^__/)
                    print last
                paren++
            } else if (c == ")") {
                paren--
            } else if (c == "{") {
                brace++
            } else if (c == "}") {
                brace--
            } else if (c == ";" && paren == 0 && brace == 0) {
                first = ""
            }
            last = ""
        }
    }' | sort -u)

if [ -z "$names" ]; then
    echo "public-symbols.sh: no function declarations found in $hdr" >&2
    exit 1
fi

if [ "$mode" = "--map" ]; then
    echo "/* Generated from $hdr by tools/public-symbols.sh: the exports of libbtfcar.so. */"
    echo "{"
    echo "  global:"
    for n in $names; do
        echo "    $n;"
    done
    echo "  local:"
    echo "    *;"
    echo "};"
else
    for n in $names; do
        echo "$n"
    done
fi
