#!/bin/sh
# Lists call cycles between the library's object files and fails if there is
# one: file A calls a function defined in file B and B (directly or through
# other files) calls back into A. docs/design.md, "Rules the layout keeps".
# Usage: tools/check-layering.sh OBJECT...   (make check-layering passes the
# library's objects)
set -eu
[ $# -gt 0 ] || { echo "usage: tools/check-layering.sh OBJECT..." >&2; exit 2; }
for o in "$@"; do
    name=${o#*/}
    nm --defined-only -g "$o" | awk -v f="$name" '$2 ~ /^[TDBRV]$/ {print "D", f, $3}'
    nm -u "$o" | awk -v f="$name" '{print "U", f, $2}'
done | awk '
    $1 == "D" { def[$3] = $2; next }
    { use[NR] = $2 " " $3 }
    END {
        # edges: file -> file that defines what it calls
        for (i in use) {
            split(use[i], p, " ")
            if ((p[2] in def) && def[p[2]] != p[1]) {
                e = p[1] SUBSEP def[p[2]]
                if (!(e in edge)) { edge[e] = p[2]; n[p[1]]++; out[p[1], n[p[1]]] = def[p[2]] }
            }
            files[p[1]] = 1
        }
        bad = 0
        # A cycle through A exists when A reaches itself: a search from each file.
        for (a in files) {
            delete seen; delete from
            top = 0; stack[++top] = a; seen[a] = 1
            while (top > 0) {
                x = stack[top--]
                for (k = 1; k <= n[x]; k++) {
                    y = out[x, k]
                    if (y == a) {
                        path = a; z = x; chain = ""
                        while (z != a) { chain = z " -> " chain; z = from[z] }
                        if (!(a in reported)) {
                            printf "call cycle: %s -> %s%s (%s)\n", a, chain, a, edge[x SUBSEP a]
                            bad = 1
                        }
                        reported[a] = 1
                    } else if (!(y in seen)) {
                        seen[y] = 1; from[y] = x; stack[++top] = y
                    }
                }
            }
        }
        if (bad) exit 1
        print "check-layering: no call cycles between object files"
    }'
