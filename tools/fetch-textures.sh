#!/bin/sh
# Extracts the photographs of stochastic textures that the fidelity bench
# (tests/bench/bench_fidelity.c, docs/fidelity.md) uses, from Debian 12's gimp-data
# package: GIMP's patterns, photographs of real surfaces, GPL-3+ (the GIMP
# authors; /usr/share/doc/gimp-data/copyright in the package). They are not
# stored in this repository; this script downloads the package from the
# Debian archive (apt-get download: no install, no root needed) and copies
# the chosen .pat files into OUTDIR.
# Usage: tools/fetch-textures.sh OUTDIR
set -eu
out=${1:?usage: tools/fetch-textures.sh OUTDIR}
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
(cd "$tmp" && apt-get download gimp-data >/dev/null 2>&1) ||
    { echo "fetch-textures: apt-get download gimp-data failed (no Debian archive?)" >&2; exit 1; }
dpkg-deb -x "$tmp"/gimp-data_*.deb "$tmp/x"
p=$tmp/x/usr/share/gimp/2.0/patterns
# gravel/ground, rock, stone, cracked stone, bark, burlap (fabric),
# crinkled paper, ice (water)
for f in Stone/ground1 Stone/rock Stone/stone33 Stone/cracked Wood/bark Fabric/burlap \
         Paper/crinklepaper Water/ice; do
    cp "$p/$f.pat" "$out/$(basename "$f").pat"
done
cp "$tmp/x/usr/share/doc/gimp-data/copyright" "$out/COPYRIGHT.gimp-data"
echo "fetch-textures: $(ls "$out"/*.pat | wc -l) patterns in $out"
