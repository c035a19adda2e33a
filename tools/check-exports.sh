#!/bin/sh
# check-exports.sh LIBRARY.so HEADER [ARCHIVE.a]
#
# Fails unless the shared library exports exactly the functions HEADER
# declares (tools/public-symbols.sh): every defined dynamic symbol must be
# one of them (internal helpers, data such as the SPIR-V arrays, C++ runtime
# pieces must stay local), and every declared function must be exported.
# With ARCHIVE (the static library), also fails on a symbol with external
# linkage named btf_ that HEADER does not declare: the library's own
# cross-file helpers are named btf__ (docs/api.md, "Names"), so that a call
# site says whether it calls the API.
set -eu
lib=${1:?usage: check-exports.sh LIBRARY.so HEADER [ARCHIVE.a]}
hdr=${2:?usage: check-exports.sh LIBRARY.so HEADER [ARCHIVE.a]}
archive=${3:-}
dir=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM

sh "$dir/public-symbols.sh" "$hdr" > "$tmp/declared"
# nm -D: "ADDRESS TYPE NAME[@VERSION]"; undefined symbols are left out.
nm -D --defined-only "$lib" | awk 'NF >= 3 { sub(/@.*/, "", $3); print $3 }' | sort -u \
    > "$tmp/exported"

status=0
extra=$(comm -23 "$tmp/exported" "$tmp/declared")
missing=$(comm -13 "$tmp/exported" "$tmp/declared")
if [ -n "$extra" ]; then
    echo "check-exports: $lib exports $(echo "$extra" | wc -l) symbol(s) that $hdr does not declare:" >&2
    echo "$extra" | sed 's/^/  /' >&2
    status=1
fi
if [ -n "$missing" ]; then
    echo "check-exports: $hdr declares $(echo "$missing" | wc -l) function(s) that $lib does not export:" >&2
    echo "$missing" | sed 's/^/  /' >&2
    status=1
fi
if [ -n "$archive" ]; then
    # nm: "ADDRESS TYPE NAME" for defined symbols, upper-case type: external.
    nm -g --defined-only "$archive" 2>/dev/null | awk 'NF == 3 && $3 ~ /^btf_/ { print $3 }' \
        | grep -v '^btf__' | sort -u > "$tmp/named"
    unprefixed=$(comm -23 "$tmp/named" "$tmp/declared")
    if [ -n "$unprefixed" ]; then
        echo "check-exports: $archive has $(echo "$unprefixed" | wc -l) internal symbol(s) named btf_ (the API's prefix; internal ones are btf__):" >&2
        echo "$unprefixed" | sed 's/^/  /' >&2
        status=1
    fi
fi
[ "$status" -eq 0 ] && echo "check-exports: $lib exports the $(wc -l < "$tmp/declared") functions of $hdr, nothing else"
exit "$status"
