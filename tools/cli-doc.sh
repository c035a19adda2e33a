#!/bin/sh
# Regenerates docs/cli.md from the commands' own --help texts:
#   sh tools/cli-doc.sh build/btfcar > docs/cli.md
set -eu
B=${1:-build/btfcar}
cat <<'HEAD'
# The btfcar command

Every command prints this text with `--help`; exit status 0 on success, 1 on
an error (one line on stderr naming the file and the problem), 2 on a usage
error. Long work draws a progress bar on stderr when it is a terminal;
`--quiet` silences it. Environment: `BTF_VK_DEVICE`, `BTF_VK_VALIDATION`,
`VK_DRIVER_FILES` (docs/gpu.md); `BTF_NOISE_PORTABLE=1` (the portable noise
loop instead of AVX2) and `BTF_SYNTH_WAVE=0` (CPU fields row by row instead
of the wavefront), both giving the same images (docs/synthesis.md);
`BTF_EXR_THREAD=0` (synthesise compresses and writes on its synthesising
thread, not beside it; the same bytes). This file is made by
tools/cli-doc.sh.

```
HEAD
"$B" --help
echo '```'
for c in generate info analyse photostereo texture-fit synthesise; do
    printf '\n## btfcar %s\n\n```\n' "$c"
    "$B" "$c" --help
    echo '```'
done
