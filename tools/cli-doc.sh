#!/bin/sh
# Regenerates docs/cli.md from the commands' own --help texts:
#   sh tools/cli-doc.sh build/btfcar > docs/cli.md
set -eu
B=${1:-build/btfcar}
cat <<'HEAD'
# The btfcar command

Every command prints this text with `--help`; exit status 0 on success, 1 on
an error (one line on stderr naming the file and the problem), 2 on a usage
error. Long work draws a progress bar on stderr when it is a terminal, and
commands print a summary and warnings there; `--quiet` silences all of it but
errors (a fit's warning about variance its model misses is in `btfcar info`
too). Environment: `BTF_VK_DEVICE`, `BTF_VK_VALIDATION`,
`VK_DRIVER_FILES` (docs/gpu.md); `BTF_NOISE_PORTABLE=1` (the portable noise
loop instead of AVX2) and `BTF_SYNTH_WAVE=0` (CPU fields row by row instead
of the wavefront), both giving the same images (docs/synthesis.md);
`BTF_EXR_THREAD=0` (synthesise compresses and writes on its synthesising
thread, not beside it; the same bytes). Numbers are plain decimals: no
leading space, no `+`, no hexadecimal, `inf` or `nan`, a `-` only where
negative values make sense (`--seed " -1"`, `+5` or `0x10` are usage errors;
`1e-320` is a number); manifests take decimals too, with a sign. This file is made by
tools/cli-doc.sh.

Outputs are checked before any work (the folder exists and takes files; no
folder where a file is wanted) and written atomically: temporary names
beside the target (`*.btfcar-tmp-ID-PID-N`), a set of files in a temporary
folder moved into place as a whole. SIGINT and SIGTERM remove the run's
temporaries and exit with 128 + the signal; stale temporaries of dead runs
are removed (docs/design.md, "Writes are atomic").

```
HEAD
"$B" --help
echo '```'
for c in generate info analyse photostereo texture-fit synthesise render compare report export; do
    printf '\n## btfcar %s\n\n```\n' "$c"
    "$B" "$c" --help
    echo '```'
done
