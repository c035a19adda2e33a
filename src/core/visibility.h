/*
 * visibility.h — the library's objects are compiled with -fvisibility=hidden
 * and with this file included first (-include, see the Makefile): the public
 * header's declarations made here keep default visibility, so libbtfcar.so
 * exports exactly the API of include/btfcar.h and nothing of the internals
 * (btf_fail, btf_alloc, the SPIR-V arrays, ...). The linker's version script
 * ($(BUILD)/gen/btfcar.map, generated from the header) says the same, and
 * `make check-exports` checks it. Users of the header need none of this.
 */
#ifndef BTF_VISIBILITY_H
#define BTF_VISIBILITY_H

#pragma GCC visibility push(default)
#include "btfcar.h"
#pragma GCC visibility pop

#endif
