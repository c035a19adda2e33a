#!/bin/sh
# public-symbols.sh HEADER [--map]
#
# Prints the names of the functions HEADER (include/btfcar.h) declares, one a
# line, sorted: the public API, and so the export list of libbtfcar.so. With
# --map, prints them as a linker version script that exports those names and
# makes every other symbol local (the Makefile's $(BUILD)/gen/btfcar.map).
#
# The names come from the header's declarations, not from a prefix (the
# library's internal helpers start with btf_ too): the header is run through
# the C preprocessor ($CC, default cc), only the lines that come from HEADER
# itself are kept (not those of the system headers it includes), and every
# identifier directly followed by "(" outside all parentheses and braces, in
# a statement that is not a typedef, is a declared function.
#
# POSIX sh and awk only.
set -eu
hdr=${1:?usage: public-symbols.sh HEADER [--map]}
mode=${2:-}

# The topical headers the umbrella includes (include/btfcar/*.h) count too.
topics="$(dirname "$hdr")/btfcar/"
names=$(${CC:-cc} -E -x c "$hdr" | awk -v want="$hdr" -v topics="$topics" '
    # Line markers: # LINE "FILE" FLAGS
    /^# [0-9]+ "/ {
        f = $3
        gsub(/"/, "", f)
        keep = (f == want || index(f, topics) == 1)
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
