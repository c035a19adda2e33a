# btfcar — build, test, benchmark, install.  `make help` lists the targets.
#
# The two commands of the README:  make demo   and   make test
# Both install missing Debian packages first (make deps).

PREFIX    ?= /usr/local
BUILD     ?= build
CC        ?= cc
CXX       ?= c++
OPT       ?= -O2 -g
SAN       ?=
PKGS      := OpenEXR vulkan cmocka

# -ffp-contract=off: no FMA contraction, so the CPU reference can match the
# GPU shaders bit for bit (docs/design.md, "Conventions", CPU/GPU parity).
# -Wno-format-truncation where the compiler knows it (GCC; clang rejects it).
NO_TRUNC  := $(shell $(CC) -Wno-format-truncation -Werror -x c -c /dev/null -o /dev/null \
               2>/dev/null && echo -Wno-format-truncation)
COMMON    := -Wall -Wextra -Werror $(NO_TRUNC) -ffp-contract=off -fPIC -pthread $(OPT) $(SAN)
CPPFLAGS  := -Iinclude -Isrc -Isrc/synth -Igpu -I$(BUILD)/gen -I/usr/include/OpenEXR -D_DEFAULT_SOURCE
CFLAGS    := -std=c11 $(COMMON)
CXXFLAGS  := -std=c++17 $(COMMON) -I/usr/include/opencv4
LDLIBS    := -lopencv_imgproc -lopencv_core -lOpenEXRCore-3_1 \
             -lpng16 -ljpeg -lvulkan -lz -lcjson -lassimp -lstdc++ -lm -lpthread
# The same for btfcar.pc: the dependencies that have a pkg-config file
# (Requires.private) and the libraries that have none (Libs.private; Debian's
# OpenCV -dev packages ship no opencv4.pc).
PC_REQUIRES_PRIVATE := OpenEXR vulkan zlib libpng libjpeg libcjson assimp
PC_LIBS_PRIVATE     := -lopencv_imgproc -lopencv_core -lstdc++ -lm -pthread

LIB_C     := $(sort $(wildcard src/*/*.c) $(wildcard gpu/*.c))
LIB_CXX   := $(sort $(wildcard src/*/*.cpp))
LIB_OBJ   := $(LIB_C:%.c=$(BUILD)/%.o) $(LIB_CXX:%.cpp=$(BUILD)/%.o)
CLI_OBJ   := $(patsubst %.c,$(BUILD)/%.o,$(sort $(wildcard cli/*.c)))
# The tests' sources: tests/unit/ (the cmocka programs, their helpers and
# scripts), tests/bench/, tests/fuzz/ (further down), tests/data/ (inputs).
# Every test and bench program is built as $(BUILD)/tests/NAME; the objects
# lie under $(BUILD)/tests/unit/ and $(BUILD)/tests/bench/.
TEST_SRC  := $(sort $(wildcard tests/unit/test_*.c))
TEST_BIN  := $(TEST_SRC:tests/unit/%.c=$(BUILD)/tests/%)
TEST_HELP := $(BUILD)/tests/unit/testutil.o
BENCH_SRC := $(sort $(wildcard tests/bench/bench_*.c))
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/tests/%)
SHADERS   := $(sort $(wildcard gpu/*.comp))
SPIRV_H   := $(SHADERS:gpu/%.comp=$(BUILD)/gen/%_spv.h)

STATIC    := $(BUILD)/libbtfcar.a
SHARED    := $(BUILD)/libbtfcar.so
CLI       := $(BUILD)/btfcar
# The browser check of HTML pages (tools/check-page.c; the report's test).
CHECK_PAGE := $(BUILD)/check-page

# The shared library's major version (docs/install.md, "Shared library and
# soname"): raised on every ABI break.
SOVERSION := 3
SONAME    := libbtfcar.so.$(SOVERSION)
# The public headers: the umbrella include/btfcar.h and the topical headers
# it includes, include/btfcar/*.h.
PUBLIC_H  := include/btfcar.h $(sort $(wildcard include/btfcar/*.h))
# The library exports exactly the functions the public headers declare: the
# objects are compiled with hidden visibility (each topical header's
# declarations are under #pragma GCC visibility push(default)), and the
# version script, made from the headers, makes everything else local.
# `make check-exports` checks it.
EXPORT_MAP := $(BUILD)/gen/btfcar.map
$(LIB_OBJ): CFLAGS += -fvisibility=hidden
$(LIB_OBJ): CXXFLAGS += -fvisibility=hidden

# Keep generated SPIR-V headers and objects between builds.
.SECONDARY:

.PHONY: all deps test test-run test-cluster asan bench demo gpu-check install uninstall fuzz fuzz-build clean help check-shaders noise-stream check-exports check-install check-layering

all: $(STATIC) $(SHARED) $(CLI) $(TEST_BIN) $(BENCH_BIN) $(BUILD)/noise_stream $(CHECK_PAGE)

help:
	@echo "make deps     install missing Debian packages (apt-get; needs root)"
	@echo "make          build the libraries, the btfcar command and the tests"
	@echo "make test     deps + build + run the whole test suite (and test-cluster)"
	@echo "make test-cluster  the Slurm test: a split sweep on a one-node cluster"
	@echo "make asan     the whole test suite under ASan + UBSan (build-asan/)"
	@echo "make demo     deps + build + generate a material and analyse it end to end"
	@echo "make bench    benchmarks (figures; never fails on time)"
	@echo "make gpu-check  on a real Vulkan GPU: parity tests, CPU vs GPU timings, one table (GPU_CHECK_FLAGS=--allow-cpu: lavapipe)"
	@echo "build/check-page PAGE.html [SHOT.png]  a page in headless Chromium: no console errors, every image shown"
	@echo "make noise-stream  build/noise_stream: raw noise words for dieharder"
	@echo "make fuzz     libFuzzer targets with clang (FUZZ_SECONDS=30 each)"
	@echo "make install  PREFIX=/usr/local: library, headers, btfcar, pkg-config file"
	@echo "make check-exports  libbtfcar.so exports exactly the functions of the public headers"
	@echo "make check-install  install into build/check-install; link a program by pkg-config"
	@echo "make check-shaders  compile every GLSL shader to SPIR-V afresh and validate it (spirv-val)"
	@echo "make check-layering  no call cycle between object files, no call up the layers of docs/design.md"

deps:
	@sh tools/install-deps.sh

# Header dependencies come from the compiler (-MMD: a .d file beside each
# object), so a header edit rebuilds only what includes it. The shaders'
# SPIR-V headers are built first (order-only): a first build has no .d file
# yet to say which objects include them.
DEPFLAGS  := -MMD -MP
$(BUILD)/%.o: %.c | $(SPIRV_H)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) -c $< -o $@

$(BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) $(DEPFLAGS) -c $< -o $@

# Shaders: GLSL -> SPIR-V as a C array, validated by spirv-val. `make
# check-shaders` compiles and validates every one of them afresh.
check-shaders:
	@rm -f $(SPIRV_H)
	@$(MAKE) --no-print-directory $(SPIRV_H) >/dev/null
	@echo "check-shaders: $(words $(SHADERS)) shaders compiled by glslangValidator and valid (spirv-val)"

$(BUILD)/gen/%_spv.h: gpu/%.comp $(wildcard gpu/*.glsl gpu/*.h src/synth/btf_*.h src/render/btf_*.h src/rf/btf_*.h)
	@mkdir -p $(dir $@)
	glslangValidator -V --target-env vulkan1.1 -Igpu -Isrc/synth -Isrc/render -Isrc/rf --vn $*_spv -o $@.spv.h $<
	glslangValidator -V --target-env vulkan1.1 -Igpu -Isrc/synth -Isrc/render -Isrc/rf -o $@.spv $<
	spirv-val --target-env vulkan1.1 $@.spv
	mv $@.spv.h $@

$(STATIC): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(EXPORT_MAP): $(PUBLIC_H) tools/public-symbols.sh
	@mkdir -p $(dir $@)
	CC="$(CC)" sh tools/public-symbols.sh include/btfcar.h --map > $@.tmp
	mv $@.tmp $@

$(SHARED): $(LIB_OBJ) $(EXPORT_MAP)
	$(CXX) -shared -Wl,-soname,$(SONAME) -Wl,--version-script=$(EXPORT_MAP) $(SAN) -o $@ \
	  $(LIB_OBJ) $(LDLIBS)

# The dynamic symbols of libbtfcar.so against the header's declarations,
# both ways: no internal symbol exported, no public function missing.
check-exports: $(SHARED) $(STATIC) $(PUBLIC_H)
	@CC="$(CC)" sh tools/check-exports.sh $(SHARED) include/btfcar.h $(STATIC)

$(CLI): $(CLI_OBJ) $(STATIC)
	$(CC) $(SAN) -pthread -o $@ $(CLI_OBJ) $(STATIC) $(LDLIBS)

$(BUILD)/tests/test_%: $(BUILD)/tests/unit/test_%.o $(TEST_HELP) $(STATIC)
	$(CC) $(SAN) -pthread $(TEST_LDFLAGS) -o $@ $< $(TEST_HELP) $(STATIC) $(LDLIBS) -lcmocka

# The benchmarks use the tests' helpers (testutil.h, scene_sphere_obj.h).
$(BUILD)/tests/bench/%.o: CPPFLAGS += -Itests/unit
$(BUILD)/tests/bench_%: $(BUILD)/tests/bench/bench_%.o $(TEST_HELP) $(STATIC)
	$(CC) $(SAN) -pthread -o $@ $< $(TEST_HELP) $(STATIC) $(LDLIBS) -lcmocka

# The fault simulator (tests/unit/test_alloc_fail.c): the library's calls of
# malloc & co. go to the test's __wrap_* functions, which fail the n-th one.
ALLOC_WRAP := -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free \
              -Wl,--wrap=aligned_alloc,--wrap=posix_memalign,--wrap=strdup,--wrap=strndup
$(BUILD)/tests/test_alloc_fail: TEST_LDFLAGS = $(ALLOC_WRAP)
# Writers taking turns (tests/unit/test_output_turns.c): the library's renames go
# through the test's __wrap_rename, which makes two writers alternate.
$(BUILD)/tests/test_output_turns: TEST_LDFLAGS = -Wl,--wrap=rename
# Writing behind without a thread (tests/unit/test_behind.c): the library's
# pthread_create goes through the test's __wrap_pthread_create, which fails
# when told to.
$(BUILD)/tests/test_behind: TEST_LDFLAGS = -Wl,--wrap=pthread_create

# No two object files of the library may call each other (docs/design.md).
check-layering: $(LIB_OBJ)
	@sh tools/check-layering.sh $(LIB_OBJ)

# Run every test program; tests/unit/run.sh prints the final "N passed, N failed".
test-run: $(TEST_BIN) $(CLI) $(CHECK_PAGE) check-exports check-layering
	@BTF_CLI=$(abspath $(CLI)) BTF_CHECK_PAGE=$(abspath $(CHECK_PAGE)) sh tests/unit/run.sh $(TEST_BIN)

test: deps
	@$(MAKE) --no-print-directory all
	@$(MAKE) --no-print-directory test-run
	@$(MAKE) --no-print-directory test-cluster

# A one-node Slurm cluster started and stopped by the test itself: a split
# sweep as a job array, merged (docs/cluster.md).
test-cluster: $(CLI)
	@BTF_CLI=$(abspath $(CLI)) sh tests/unit/test_slurm.sh

asan: deps
	@$(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer" \
	  SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/unit/lsan.supp:print_suppressions=0 \
	  BTF_ASAN=1 $(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer" \
	  SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" test-run

bench: deps
	@$(MAKE) --no-print-directory all
	@BTF_CLI=$(abspath $(CLI)) sh tests/bench/bench.sh $(BENCH_BIN)

# The real-GPU check (tools/gpu-check.sh, docs/gpu.md): the GPU parity tests
# on the best Vulkan device, then CPU against GPU timings of four workloads
# in one table. Without a real GPU it says so and passes;
# GPU_CHECK_FLAGS=--allow-cpu runs it on lavapipe.
GPU_CHECK_FLAGS ?=
gpu-check: all
	@BTF_CLI=$(abspath $(CLI)) BTF_CHECK_PAGE=$(abspath $(CHECK_PAGE)) \
	  sh tools/gpu-check.sh $(GPU_CHECK_FLAGS)

demo: deps
	@$(MAKE) --no-print-directory all
	@sh examples/demo.sh $(abspath $(CLI))

# libFuzzer targets: every tests/fuzz/fuzz_*.c becomes $(FUZZ_BUILD)/fuzz_NAME,
# linked (by clang++) with the whole library, whose C sources clang compiles
# and whose C++ bridge clang++ compiles, all with ASan + UBSan and coverage
# instrumentation. tests/fuzz/fuzz.sh then runs each for FUZZ_SECONDS from
# its seed corpus (tests/fuzz/corpus/NAME/) and fails if any input crashes.
# Warnings are shown but not fatal here: gcc's -Werror build is the gate.
# The small EXR chunk limit (BTF_EXR_MAX_CHUNK_BYTES) keeps the chunk
# buffers of src/io/exr_read.c under libFuzzer's memory limit.
FUZZ_SECONDS ?= 30
FUZZ_BUILD   ?= build-fuzz
FUZZ_SRC     := $(sort $(wildcard tests/fuzz/fuzz_*.c))
FUZZ_BIN     := $(FUZZ_SRC:tests/fuzz/%.c=$(FUZZ_BUILD)/%)
FUZZ_OBJ     := $(LIB_C:%.c=$(FUZZ_BUILD)/%.o) $(LIB_CXX:%.cpp=$(FUZZ_BUILD)/%.o)
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=undefined
FUZZ_FLAGS   := -g -O1 -fno-omit-frame-pointer -ffp-contract=off -pthread -Wall -Wextra \
                -DBTF_EXR_MAX_CHUNK_BYTES='(64u << 20)'

$(FUZZ_BUILD)/%.o: %.c | $(SPIRV_H)
	@mkdir -p $(dir $@)
	clang $(CPPFLAGS) -std=c11 $(FUZZ_FLAGS) $(DEPFLAGS) -fsanitize=fuzzer-no-link $(FUZZ_SAN) -c $< -o $@

$(FUZZ_BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	clang++ $(CPPFLAGS) -std=c++17 -I/usr/include/opencv4 $(FUZZ_FLAGS) $(DEPFLAGS) \
	  -fsanitize=fuzzer-no-link $(FUZZ_SAN) -c $< -o $@

$(FUZZ_BUILD)/fuzz_%: tests/fuzz/fuzz_%.c $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	clang $(CPPFLAGS) -std=c11 $(FUZZ_FLAGS) -fsanitize=fuzzer $(FUZZ_SAN) -c $< -o $@.o
	clang++ -fsanitize=fuzzer $(FUZZ_SAN) -pthread -o $@ $@.o $(FUZZ_OBJ) $(LDLIBS)

# Keep the objects (pattern-rule intermediates) so rebuilds are incremental.
# (A .SECONDARY with a list makes only those secondary: the test objects too.)
.SECONDARY: $(FUZZ_OBJ) $(SPIRV_H) $(TEST_SRC:%.c=$(BUILD)/%.o) $(BENCH_SRC:%.c=$(BUILD)/%.o) $(TEST_HELP)

fuzz-build: $(FUZZ_BIN)

fuzz: deps
	@$(MAKE) --no-print-directory fuzz-build
	@sh tests/fuzz/fuzz.sh $(FUZZ_SECONDS) $(FUZZ_BIN)

# The headers: PREFIX/include/btfcar.h and PREFIX/include/btfcar/*.h.
install: $(STATIC) $(SHARED) $(CLI)
	install -d $(DESTDIR)$(PREFIX)/lib $(DESTDIR)$(PREFIX)/include/btfcar $(DESTDIR)$(PREFIX)/bin \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 $(STATIC) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SHARED) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libbtfcar.so
	install -m 644 include/btfcar.h $(DESTDIR)$(PREFIX)/include/
	install -m 644 $(filter include/btfcar/%,$(PUBLIC_H)) $(DESTDIR)$(PREFIX)/include/btfcar/
	install -m 755 $(CLI) $(DESTDIR)$(PREFIX)/bin/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@REQUIRES_PRIVATE@|$(PC_REQUIRES_PRIVATE)|' \
	  -e 's|@LIBS_PRIVATE@|$(PC_LIBS_PRIVATE)|' -e 's|@VERSION@|$(shell sed -n 's/.*BTF_VERSION_STRING "\(.*\)"/\1/p' include/btfcar/base.h)|' \
	  btfcar.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/btfcar.pc

# Installs into $(BUILD)/check-install and builds a small program with
# `pkg-config btfcar`, shared and --static (tools/check-install.sh).
check-install: $(STATIC) $(SHARED) $(CLI)
	@rm -rf $(BUILD)/check-install
	@$(MAKE) --no-print-directory install DESTDIR= PREFIX=$(abspath $(BUILD))/check-install >/dev/null
	@CC="$(CC)" sh tools/check-install.sh $(abspath $(BUILD))/check-install

uninstall:
	rm -f $(DESTDIR)$(PREFIX)/lib/libbtfcar.a $(DESTDIR)$(PREFIX)/lib/libbtfcar.so* \
	  $(DESTDIR)$(PREFIX)/include/btfcar.h $(DESTDIR)$(PREFIX)/bin/btfcar \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig/btfcar.pc \
	  $(addprefix $(DESTDIR)$(PREFIX)/,$(filter include/btfcar/%,$(PUBLIC_H)))
	rmdir $(DESTDIR)$(PREFIX)/include/btfcar 2>/dev/null || true

clean:
	rm -rf build build-asan build-fuzz

# The synthesis loops are written to be vectorised (src/synth/); -O3 lets
# GCC do it. The op order per pixel is fixed, so results do not change.
SYNTH_O3  := $(patsubst %.c,$(BUILD)/%.o,$(wildcard src/synth/*.c))
$(SYNTH_O3): CFLAGS += -O3
# The noise generator's four Box-Muller vectors in lock step run out of the
# 16 vector registers; scheduling before register allocation, with an eye on
# register pressure, makes it about 8 % faster (same instructions, same bits).
# GCC options: added only where the compiler takes them (clang does not).
SCHED_FLAGS := $(shell $(CC) -fschedule-insns -fsched-pressure -Werror -x c -c /dev/null \
                 -o /dev/null 2>/dev/null && echo -fschedule-insns -fsched-pressure)
$(BUILD)/src/synth/noise_row.o $(BUILD)/src/synth/wave.o: CFLAGS += $(SCHED_FLAGS)

# Opens an HTML page in headless Chromium (Debian's chromium, from make deps)
# over the DevTools protocol and fails on console errors or warnings, failed
# loads and images that do not decode; takes a screenshot. Not part of the
# library: build/check-page [--size WxH] [--timeout S] PAGE.html [SHOT.png]
$(CHECK_PAGE): tools/check-page.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $< -lcjson

# The raw words of one synthesis noise stream, for statistical test suites
# (docs/synthesis.md, "Noise"): build/noise_stream | dieharder -a -g 200
noise-stream: $(BUILD)/noise_stream

$(BUILD)/noise_stream: tools/noise_stream.c src/synth/btf_noise.h src/synth/btf_shared.h
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $<

# The compiler's header dependencies (see DEPFLAGS above).
-include $(shell find $(BUILD) $(FUZZ_BUILD) -name '*.d' 2>/dev/null)
