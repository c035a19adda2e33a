#!/bin/sh
# Lists call cycles between the library's object files and fails if there is
# one: file A calls a function defined in file B and B (directly or through
# other files) calls back into A. Then fails on any call from a folder into
# a folder above it in the layers docs/design.md lists on its line
# "Layers, bottom to top: ..." (a folder missing from that line fails too).
# docs/design.md, "Rules the layout keeps".
# Usage: tools/check-layering.sh OBJECT...   (make check-layering passes the
# library's objects)
set -eu
[ $# -gt 0 ] || { echo "usage: tools/check-layering.sh OBJECT..." >&2; exit 2; }
doc=${LAYERS_DOC:-docs/design.md}
layers=$(sed -n 's/^Layers, bottom to top: *//p' "$doc" | tr -d '`,.')
[ -n "$layers" ] || { echo "check-layering: $doc has no line 'Layers, bottom to top: ...'" >&2; exit 2; }
for o in "$@"; do
    name=${o#*/}
    nm --defined-only -g "$o" | awk -v f="$name" '$2 ~ /^[TDBRV]$/ {print "D", f, $3}'
    nm -u "$o" | awk -v f="$name" '{print "U", f, $2}'
done | awk -v layers="$layers" '
    # The folder of an object: src/FOLDER/x.o, or gpu for gpu/x.o.
    function folder(f,    p) {
        split(f, p, "/")
        return p[1] == "src" ? p[2] : p[1]
    }
    BEGIN { n_layers = split(layers, l, " "); for (i = 1; i <= n_layers; i++) rank[l[i]] = i }
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
        # Calls go down the layers, never up.
        for (e in edge) {
            split(e, q, SUBSEP)
            a = folder(q[1]); b = folder(q[2])
            if (a == b) continue
            if (!(a in rank) || !(b in rank)) {
                printf "layering: folder %s is not in the layers of the design\n", (a in rank) ? b : a
                bad = 1
            } else if (rank[a] < rank[b]) {
                printf "layering: %s calls %s of %s, a layer above %s\n", q[1], edge[e], q[2], a
                bad = 1
            }
        }
        if (bad) exit 1
        print "check-layering: no call cycles between object files; every call goes down the layers"
    }'
