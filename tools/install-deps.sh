#!/bin/sh
# Installs the Debian 12 packages btfcar needs, and only those that are missing.
# Idempotent: when everything is present it runs no apt command at all.
set -eu

# chromium: the browser test of `btfcar report` (build/check-page, tools/check-page.c).
# slurm-wlm, munge: the cluster test (tests/unit/test_slurm.sh, docs/cluster.md).
PKGS="build-essential g++ pkg-config clang
libopencv-core-dev libopencv-imgproc-dev
libopenexr-dev libpng-dev libjpeg62-turbo-dev
libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
glslang-tools spirv-tools
libcmocka-dev zlib1g-dev time openexr
libcjson-dev libassimp-dev
chromium
slurm-wlm munge"

missing=""
for p in $PKGS; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done

if [ -z "$missing" ]; then
    echo "deps: all packages present"
    exit 0
fi

echo "deps: installing:$missing"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        SUDO="sudo"
    else
        echo "deps: missing packages ($missing) and not root; run as root or install them" >&2
        exit 1
    fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
# shellcheck disable=SC2086
$SUDO apt-get install -y --no-install-recommends $missing </dev/null
