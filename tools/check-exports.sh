#!/bin/sh
# check-exports.sh LIBRARY.so HEADER
#
# Fails unless the shared library exports exactly the functions HEADER
# declares (tools/public-symbols.sh): every defined dynamic symbol must be
# one of them (internal helpers, data such as the SPIR-V arrays, C++ runtime
# pieces must stay local), and every declared function must be exported.
set -eu
lib=${1:?usage: check-exports.sh LIBRARY.so HEADER}
hdr=${2:?usage: check-exports.sh LIBRARY.so HEADER}
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
[ "$status" -eq 0 ] && echo "check-exports: $lib exports the $(wc -l < "$tmp/declared") functions of $hdr, nothing else"
exit "$status"
