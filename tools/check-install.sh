#!/bin/sh
# check-install.sh PREFIX
#
# After `make install PREFIX=...` (the Makefile's check-install target does
# both): every installed header (btfcar.h and each topical header
# btfcar/NAME.h) compiles alone, as C11 and as C++ (its extern "C" guard),
# with nothing but `pkg-config --cflags btfcar`; a small program that uses
# the installed headers compiles and links against the installed library
# with nothing but `pkg-config btfcar`, once with the shared library and
# once statically with libbtfcar.a (--static: Requires.private and
# Libs.private), and both run.
set -eu
prefix=${1:?usage: check-install.sh PREFIX}
cc=${CC:-cc}
cxx=${CXX:-c++}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"

# Each header stands alone: it includes what it needs.
n=0
for h in "$prefix/include/btfcar.h" "$prefix"/include/btfcar/*.h; do
    name=${h#"$prefix/include/"}
    printf '#include <%s>\n' "$name" > "$tmp/h.c"
    # shellcheck disable=SC2046
    if ! "$cc" -std=c11 -Wall -Wextra -Werror -fsyntax-only $(pkg-config --cflags btfcar) \
            "$tmp/h.c"; then
        echo "check-install: <$name> does not compile alone (C11)" >&2
        exit 1
    fi
    if command -v "$cxx" > /dev/null 2>&1; then
        cp "$tmp/h.c" "$tmp/h.cpp"
        # shellcheck disable=SC2046
        if ! "$cxx" -std=c++17 -Wall -Wextra -Werror -fsyntax-only \
                $(pkg-config --cflags btfcar) "$tmp/h.cpp"; then
            echo "check-install: <$name> does not compile alone (C++)" >&2
            exit 1
        fi
    fi
    n=$((n + 1))
done

# One topical header and the umbrella together (include guards).
cat > "$tmp/t.c" <<'C'
#include <btfcar/base.h>
#include <btfcar.h>
#include <stdio.h>
#include <string.h>
int main(void)
{
    btf_dirset s;
    btf_error e;
    memset(&e, 0, sizeof e);
    if (btf_dirset_ubo81(&s, &e) != 0 || s.count != 81) {
        fprintf(stderr, "btf_dirset_ubo81: %s\n", e.msg);
        return 1;
    }
    btf_dirset_free(&s);
    printf("btfcar %s\n", BTF_VERSION_STRING);
    return 0;
}
C

# Shared: the loader must find libbtfcar.so.MAJOR in PREFIX/lib.
# shellcheck disable=SC2046
"$cc" -o "$tmp/t_shared" "$tmp/t.c" $(pkg-config --cflags --libs btfcar)
LD_LIBRARY_PATH="$prefix/lib" "$tmp/t_shared" > /dev/null
if ! LD_LIBRARY_PATH="$prefix/lib" ldd "$tmp/t_shared" | grep -q "libbtfcar\.so\."; then
    echo "check-install: the shared build does not use libbtfcar.so" >&2
    exit 1
fi

# Static: libbtfcar.a and its private dependencies (shared themselves).
libs=$(pkg-config --static --libs btfcar | sed 's/-lbtfcar/-Wl,-Bstatic -lbtfcar -Wl,-Bdynamic/')
# shellcheck disable=SC2046,SC2086
"$cc" -o "$tmp/t_static" "$tmp/t.c" $(pkg-config --cflags btfcar) $libs
"$tmp/t_static" > /dev/null
if ldd "$tmp/t_static" | grep -q "libbtfcar\.so"; then
    echo "check-install: the static build still needs libbtfcar.so" >&2
    exit 1
fi
echo "check-install: $n headers compile alone; pkg-config btfcar links and runs," \
    "shared and --static ($prefix)"
