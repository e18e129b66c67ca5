# Four single-header libraries, their tests, benchmarks and examples.
#
#   make          build the examples
#   make test     install the reference libraries if needed, compile-check every
#                 header, run unit tests (ASan+UBSan; again with clang's UBSan
#                 when clang is present), replay the fuzz corpora, run reference tests
#   make bench    run the benchmarks (throughput next to the papers' figures)
#   make demo     run the main example (make demo-daylight: the building by day)
#   make fuzz     run every fuzz target for FUZZ_SECONDS (default 60) with libFuzzer
#   make fuzz-corpus  rewrite the fuzz seeds from the headers' save functions
#   make view     the walkthrough in a window (installs SDL2 if needed and it can)
#   make clean
#
# Files are found by name, so adding one needs no edit here:
#   tests/test_*.c    unit tests: headers only, run under ASan+UBSan
#   tests/tsan_*.c    concurrency tests: headers only, run under ThreadSanitizer
#   tests/ref_*.c     reference tests: linked with tests/reference (Embree, OpenEXR)
#   tests/bench_*.c   benchmarks: optimised, linked with tests/reference
#   examples/*.c      examples: one program each, `cc examples/x.c -lm` builds it
#                     (but examples/viewer.c, built with SDL2 when sdl2-config is found)
#   tests/check_*.py  checks of the generated data (python3), run by make test
#   tests/assimp_*.c  unit tests that need Assimp: built and run only when it is present
#   tests/fuzz/fuzz_*.c  fuzz targets (tests/fuzz/fuzz.h), corpus tests/fuzz/corpus/*

CC      ?= cc
CXX     ?= g++
CLANG   := $(shell command -v clang 2>/dev/null)
CLANGXX := $(shell command -v clang++ 2>/dev/null)
NPROC   := $(shell nproc 2>/dev/null || echo 2)

BUILD   := build
HEADERS := irrvol.h radinterp.h lightvec.h rendercache.h
WARN    := -Wall -Wextra -pedantic -Werror
CFLAGS_PROJECT := -std=c99 $(WARN) -I.
SAN     := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# Debug information of the test and reference programs: line tables only.
# Sanitizer reports and backtraces keep their files and lines; full -g (the
# variables' locations too) made each ASan build of a walkthrough test a
# third slower to compile (54 against 35 s of CPU), and compiling is about half
# of `make test`. `make TEST_DEBUG=-g` for a debugger's view of locals.
TEST_DEBUG ?= -g1
LIBS    := -lm -lpthread
OPT     := -O2
BENCH_OPT ?= -O3 -march=native
# The examples' flags (make demo EXAMPLE_OPT=-O3 to try others). -O3 was
# measured against -O2 and not kept: the house's precompute on two threads
# took 110.9 against 109.7 s (medians of 4 alternated runs), the office's
# on one thread 0.92x the CPU time, for 28 s more CPU to compile the examples.
EXAMPLE_OPT ?= -O2

# Every program depends on every project header: headers are the product.
ALL_H := $(HEADERS) $(wildcard tests/*.h tests/reference/*.h examples/common/*.h)

UNIT_BINS    := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/test_*.c))
TSAN_BINS    := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/tsan_*.c))
REF_BINS     := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/ref_*.c))
BENCH_BINS   := $(patsubst tests/%.c,$(BUILD)/bench/%,$(wildcard tests/bench_*.c))
EXAMPLE_BINS := $(patsubst examples/%.c,$(BUILD)/examples/%,$(filter-out examples/viewer.c,$(wildcard examples/*.c)))
# The interactive viewer and its sanitized build for tests/test_viewer.c,
# only where SDL2 is installed (tests/deps_viewer.sh installs it when it can).
VIEWER_BINS  := $(if $(shell command -v sdl2-config 2>/dev/null),$(BUILD)/examples/viewer $(BUILD)/tests/viewer_asan)
REF_OBJS     := $(patsubst tests/reference/%.c,$(BUILD)/ref/%.o,$(wildcard tests/reference/*.c))
LINKAGE_BIN  := $(BUILD)/tests/linkage
DATA_CHECKS  := $(wildcard tests/check_*.py)

# The generated buildings: the 1k and 4k presets are committed under
# examples/data, the larger ones are written here for the benchmarks.
BUILDINGS    := $(BUILD)/data/building_16k.obj $(BUILD)/data/building_64k.obj

# Assimp (optional): when libassimp-dev is present (make deps installs it when
# it can) the examples read every format it reads and tests/assimp_*.c run.
ASSIMP_OK    := $(shell pkg-config --exists assimp 2>/dev/null && echo yes)
ASSIMP_FLAGS := $(if $(ASSIMP_OK),-DEX_HAVE_ASSIMP $(shell pkg-config --cflags assimp))
ASSIMP_LIBS  := $(if $(ASSIMP_OK),$(shell pkg-config --libs assimp))
ASSIMP_BINS  := $(if $(ASSIMP_OK),$(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/assimp_*.c)))
# Programs are built again when Assimp comes or goes: this file changes then.
ASSIMP_STAMP := $(BUILD)/.assimp-flags
$(shell mkdir -p $(BUILD) && echo '$(ASSIMP_FLAGS) $(ASSIMP_LIBS)' | cmp -s - $(ASSIMP_STAMP) || \
        echo '$(ASSIMP_FLAGS) $(ASSIMP_LIBS)' > $(ASSIMP_STAMP))

# Fuzz targets (tests/fuzz/fuzz.h), each built twice: replay_NAME replays the
# committed corpus tests/fuzz/corpus/NAME under ASan+UBSan with any compiler
# (make test); fuzz_NAME is the libFuzzer program (clang, make fuzz).
FUZZ_NAMES   := $(patsubst tests/fuzz/fuzz_%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
REPLAY_BINS  := $(patsubst %,$(BUILD)/fuzz/replay_%,$(FUZZ_NAMES))
FUZZ_BINS    := $(patsubst %,$(BUILD)/fuzz/fuzz_%,$(FUZZ_NAMES))
FUZZ_SECONDS ?= 60

# With clang present, make test runs the unit tests a second time, built by
# clang with UBSan alone (ASan is the gcc run's job), for the checks gcc's
# -fsanitize=undefined lacks; the fuzz targets use the same checks:
# - float-cast-overflow (in clang's "undefined" group): a float converted to
#   an integer type that cannot hold it, e.g. (int)ceilf of a huge projection;
# - pointer-overflow's "applying zero offset to null pointer";
# - implicit-conversion: implicit integer conversions that change the value
#   (truncation to a narrower type, a negative value made unsigned), the
#   32/64-bit size mistakes a loader must not make. Explicit casts are not
#   checked, so narrowing on purpose is written as a cast.
# Left out: unsigned-integer-overflow and unsigned-shift-base (defined
# behaviour the hashes, CRCs and counter-based random streams rely on: the
# unit tests report about 80 places) and float-divide-by-zero (IEEE 754
# gives inf; branchless code divides first and masks the result after, as
# rendercache's projection of points behind the eye does).
CLANG_UBSAN := -fsanitize=undefined,implicit-conversion -fno-sanitize-recover=all -fno-omit-frame-pointer
# The unit tests' run leaves pointer-overflow out until radinterp_build_mesh no
# longer adds 0 to a null pointer for a patch without discontinuities (issue
# 17, item 7); gcc's run checks every other pointer overflow meanwhile.
CLANG_UBSAN_PENDING := -fno-sanitize=pointer-overflow
CLANG_UBSAN_BINS := $(if $(CLANG),$(patsubst tests/%.c,$(BUILD)/clang-ubsan/%-clang-ubsan,$(wildcard tests/test_*.c)))
# The kernels behind __AVX__ and __FMA__ (lightvec's kd-tree node test of
# eight children at once, the BVHs' fused multiply-adds) are compiled only
# with those flags: where this machine runs AVX2 and FMA, lightvec's cache
# tests (lookups against a brute-force scan) run once more built with them.
HOST_AVX2 := $(shell grep -qw avx2 /proc/cpuinfo 2>/dev/null && grep -qw fma /proc/cpuinfo && echo yes)
AVX2_BINS := $(if $(HOST_AVX2),$(BUILD)/avx2/test_lightvec_cache-avx2)

# Compile checks: each header with its implementation, as C99, C11 and C++,
# with gcc and (when present) clang, and once as static.
CHECK_KINDS := c99 c11 cxx static
ifneq ($(CLANG),)
CHECK_KINDS += clang-c99
endif
ifneq ($(CLANGXX),)
CHECK_KINDS += clang-cxx
endif
CHECK_OBJS := $(foreach h,$(basename $(HEADERS)),$(foreach k,$(CHECK_KINDS),$(BUILD)/check/$(h).$(k).o))
# The examples' headers as C++ too (g++ and clang++), each included twice;
# scene_assimp.h only where Assimp is present, with its flags.
EXAMPLE_CHECK_H := $(basename $(notdir $(filter-out $(if $(ASSIMP_OK),,examples/common/scene_assimp.h),\
                     $(wildcard examples/common/*.h))))
CHECK_OBJS += $(foreach h,$(EXAMPLE_CHECK_H),$(foreach k,$(filter cxx clang-cxx,$(CHECK_KINDS)),$(BUILD)/check/example_$(h).$(k).o))

# The reference libraries are looked up only after tests/deps.sh ran.
REF_CFLAGS = $(shell pkg-config --cflags OpenEXR 2>/dev/null)
REF_LIBS   = -lembree3 $(shell pkg-config --libs OpenEXR 2>/dev/null)

.SECONDARY:
.PHONY: all examples test test-build test-run bench bench-build demo demo-daylight view deps viewer-deps clean fuzz fuzz-build fuzz-corpus

all: examples
examples: $(EXAMPLE_BINS) $(filter $(BUILD)/examples/%,$(VIEWER_BINS))

test: deps viewer-deps
	@$(MAKE) --no-print-directory -j$(NPROC) test-build
	@$(MAKE) --no-print-directory test-run

# A make of its own after deps: Assimp may just have been installed.
test-run:
	@tests/run.sh $(DATA_CHECKS) $(LINKAGE_BIN) $(UNIT_BINS) $(CLANG_UBSAN_BINS) $(AVX2_BINS) $(REPLAY_BINS) $(TSAN_BINS) \
	    $(REF_BINS) $(ASSIMP_BINS)

test-build: $(CHECK_OBJS) $(LINKAGE_BIN) $(UNIT_BINS) $(CLANG_UBSAN_BINS) $(AVX2_BINS) $(REPLAY_BINS) $(TSAN_BINS) $(REF_BINS) \
            $(ASSIMP_BINS) $(EXAMPLE_BINS) $(VIEWER_BINS)

bench: deps
	@$(MAKE) --no-print-directory -j$(NPROC) bench-build $(BUILDINGS)
	@for b in $(BENCH_BINS); do echo "== $$(basename $$b)"; $$b || exit 1; done

bench-build: $(BENCH_BINS)

# The main job. Runs the walkthrough once it exists, else the scene viewer.
DEMO := $(if $(wildcard examples/walkthrough.c),$(BUILD)/examples/walkthrough,$(BUILD)/examples/scene_view)
demo: $(DEMO)
	@mkdir -p $(BUILD)/demo
	$(DEMO) --out $(BUILD)/demo

# The building by day: glass in the windows, a sky (mode raytrace).
demo-daylight: $(BUILD)/examples/walkthrough
	@mkdir -p $(BUILD)/demo
	$(BUILD)/examples/walkthrough --scene daylight --mode raytrace --out $(BUILD)/demo

# The walkthrough in a window: mouse and WASD, M switches the mode (see examples/viewer.c).
view: viewer-deps
	@command -v sdl2-config >/dev/null 2>&1 || { echo "make view: SDL2 is missing (apt-get install libsdl2-dev)" >&2; exit 1; }
	@$(MAKE) --no-print-directory $(BUILD)/examples/viewer
	$(BUILD)/examples/viewer

viewer-deps:
	@tests/deps_viewer.sh

deps: $(BUILD)/.deps-ok $(BUILD)/.deps-assimp-tried
$(BUILD)/.deps-ok: tests/deps.sh
	@CC=$(CC) tests/deps.sh
	@mkdir -p $(BUILD) && touch $@
$(BUILD)/.deps-assimp-tried: tests/deps_assimp.sh
	@CC=$(CC) tests/deps_assimp.sh
	@mkdir -p $(BUILD) && touch $@

# --- compile checks -------------------------------------------------------
$(BUILD)/check/%.c: | $(BUILD)/check
	@up=$$(echo $* | tr a-z A-Z); \
	 printf '#define %s_IMPLEMENTATION\n#include "%s.h"\n#include "%s.h" /* included twice on purpose */\n' $$up $* $* > $@
$(BUILD)/check/%.c99.o: $(BUILD)/check/%.c %.h
	$(CC) -std=c99 $(WARN) -I. -c $< -o $@
$(BUILD)/check/%.c11.o: $(BUILD)/check/%.c %.h
	$(CC) -std=c11 $(WARN) -I. -c $< -o $@
$(BUILD)/check/%.cxx.o: $(BUILD)/check/%.c %.h
	$(CXX) -x c++ $(WARN) -I. -c $< -o $@
$(BUILD)/check/%.static.o: $(BUILD)/check/%.c %.h
	$(CC) -std=c99 $(WARN) -Wno-unused-function -I. -D$(shell echo $* | tr a-z A-Z)_STATIC -c $< -o $@
$(BUILD)/check/%.clang-c99.o: $(BUILD)/check/%.c %.h
	$(CLANG) -std=c99 $(WARN) -I. -c $< -o $@
$(BUILD)/check/%.clang-cxx.o: $(BUILD)/check/%.c %.h
	$(CLANGXX) -x c++ $(WARN) -I. -c $< -o $@
$(BUILD)/check/example_%.cpp: | $(BUILD)/check
	@printf '#include "examples/common/%s.h"\n#include "examples/common/%s.h" /* included twice on purpose */\n' $* $* > $@
$(BUILD)/check/example_%.cxx.o: $(BUILD)/check/example_%.cpp $(ALL_H) $(ASSIMP_STAMP)
	$(CXX) -x c++ $(WARN) -I. $(ASSIMP_FLAGS) -c $< -o $@
$(BUILD)/check/example_%.clang-cxx.o: $(BUILD)/check/example_%.cpp $(ALL_H) $(ASSIMP_STAMP)
	$(CLANGXX) -x c++ $(WARN) -I. $(ASSIMP_FLAGS) -c $< -o $@

# --- tests ----------------------------------------------------------------
$(LINKAGE_BIN): tests/linkage/impl.c tests/linkage/main.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) $(OPT) tests/linkage/impl.c tests/linkage/main.c -o $@ $(LIBS)

$(BUILD)/tests/test_%: tests/test_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) $< -o $@ $(LIBS)

# The walkthrough's tests and the viewer's sanitized build link the four
# headers' implementations from one object per compiler and sanitizer
# (WT_LIBRARIES_LINKED, examples/common/walkthrough.h): compiling them was 29
# of the 33 s of CPU each of these programs took to build.
WT_PROGRAMS := test_viewer $(patsubst tests/%.c,%,$(wildcard tests/test_walkthrough*.c))
LIBRARIES_C := $(BUILD)/tests/libraries.c
$(LIBRARIES_C): | $(BUILD)/tests
	@printf '#define IRRVOL_IMPLEMENTATION\n#define LIGHTVEC_IMPLEMENTATION\n#define RENDERCACHE_IMPLEMENTATION\n#define RADINTERP_IMPLEMENTATION\n#include "irrvol.h"\n#include "lightvec.h"\n#include "rendercache.h"\n#include "radinterp.h"\n' > $@
$(BUILD)/tests/libraries.o: $(LIBRARIES_C) $(HEADERS) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) -c $< -o $@
$(patsubst %,$(BUILD)/tests/%,$(WT_PROGRAMS)): $(BUILD)/tests/%: tests/%.c $(BUILD)/tests/libraries.o $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) -DWT_LIBRARIES_LINKED $< $(BUILD)/tests/libraries.o -o $@ $(LIBS)

$(BUILD)/tests/assimp_%: tests/assimp_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) $(ASSIMP_FLAGS) $< -o $@ $(LIBS) $(ASSIMP_LIBS)

$(BUILD)/tests/tsan_%: tests/tsan_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) -fsanitize=thread $< -o $@ $(LIBS)

$(BUILD)/tests/ref_%: tests/ref_%.c $(REF_OBJS) $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) $(OPT) $(TEST_DEBUG) $(REF_CFLAGS) $< $(REF_OBJS) -o $@ $(REF_LIBS) $(LIBS)

# C11: OpenEXR's C API uses anonymous unions.
$(BUILD)/ref/%.o: tests/reference/%.c $(ALL_H) | $(BUILD)/ref
	$(CC) -std=c11 $(WARN) -I. $(OPT) $(TEST_DEBUG) $(REF_CFLAGS) -c $< -o $@

$(BUILD)/bench/bench_%: tests/bench_%.c $(REF_OBJS) $(ALL_H) | $(BUILD)/bench
	$(CC) $(CFLAGS_PROJECT) $(BENCH_OPT) $(REF_CFLAGS) $< $(REF_OBJS) -o $@ $(REF_LIBS) $(LIBS)

# irrvol's query rates are promised with the flags a user would build with.
$(BUILD)/bench/bench_irrvol: BENCH_OPT = -O2

$(BUILD)/data/building_%.obj: examples/data/make_building.py | $(BUILD)/data
	python3 examples/data/make_building.py --preset $* --out $(BUILD)/data/building_$*

# --- clang's UBSan run and fuzzing ----------------------------------------
$(BUILD)/clang-ubsan/%-clang-ubsan: tests/%.c $(ALL_H) | $(BUILD)/clang-ubsan
	$(CLANG) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(CLANG_UBSAN) $(CLANG_UBSAN_PENDING) $< -o $@ $(LIBS)

$(BUILD)/clang-ubsan/libraries.o: $(LIBRARIES_C) $(HEADERS) | $(BUILD)/clang-ubsan
	$(CLANG) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(CLANG_UBSAN) $(CLANG_UBSAN_PENDING) -c $< -o $@
$(patsubst %,$(BUILD)/clang-ubsan/%-clang-ubsan,$(WT_PROGRAMS)): $(BUILD)/clang-ubsan/%-clang-ubsan: tests/%.c \
        $(BUILD)/clang-ubsan/libraries.o $(ALL_H) | $(BUILD)/clang-ubsan
	$(CLANG) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(CLANG_UBSAN) $(CLANG_UBSAN_PENDING) -DWT_LIBRARIES_LINKED $< \
	    $(BUILD)/clang-ubsan/libraries.o -o $@ $(LIBS)

$(BUILD)/avx2/%-avx2: tests/%.c $(ALL_H) | $(BUILD)/avx2
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) -mavx2 -mfma $< -o $@ $(LIBS)

# The replays use the fuzzers' sanitizers when clang is present, else gcc's.
REPLAY_CC := $(if $(CLANG),$(CLANG) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) -fsanitize=address $(CLANG_UBSAN),$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN))
$(BUILD)/fuzz/replay_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c tests/fuzz/fuzz.h $(ALL_H) | $(BUILD)/fuzz
	$(REPLAY_CC) $< tests/fuzz/replay.c -o $@ $(LIBS)

$(BUILD)/fuzz/fuzz_%: tests/fuzz/fuzz_%.c tests/fuzz/fuzz.h $(ALL_H) | $(BUILD)/fuzz
	$(CLANG) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) -fsanitize=fuzzer,address $(CLANG_UBSAN) $< -o $@ $(LIBS)

# Installs clang's fuzzer runtime when it is missing and it can
# (tests/deps_fuzz.sh); otherwise says what to install and skips.
fuzz:
	@if tests/deps_fuzz.sh; then \
	    $(MAKE) --no-print-directory -j$(NPROC) fuzz-build && \
	    tests/fuzz/run.sh $(FUZZ_SECONDS) $(BUILD) $(FUZZ_BINS); \
	 else echo "fuzz: skipped: clang cannot build libFuzzer programs here (see above)"; fi

fuzz-build: $(FUZZ_BINS) $(REPLAY_BINS)

fuzz-corpus: $(BUILD)/fuzz/make_corpus
	$(BUILD)/fuzz/make_corpus tests/fuzz/corpus

$(BUILD)/fuzz/make_corpus: tests/fuzz/make_corpus.c tests/fuzz/fuzz.h $(ALL_H) | $(BUILD)/fuzz
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) $< -o $@ $(LIBS)

# --- examples -------------------------------------------------------------
$(BUILD)/examples/%: examples/%.c $(ALL_H) $(ASSIMP_STAMP) | $(BUILD)/examples
	$(CC) $(CFLAGS_PROJECT) $(EXAMPLE_OPT) $(ASSIMP_FLAGS) $< -o $@ $(LIBS) $(ASSIMP_LIBS)

$(BUILD)/examples/viewer: examples/viewer.c $(ALL_H) $(ASSIMP_STAMP) | $(BUILD)/examples
	$(CC) $(CFLAGS_PROJECT) $(EXAMPLE_OPT) $(ASSIMP_FLAGS) $$(sdl2-config --cflags) $< -o $@ $$(sdl2-config --libs) $(LIBS) $(ASSIMP_LIBS)

$(BUILD)/tests/viewer_asan: examples/viewer.c $(BUILD)/tests/libraries.o $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 $(TEST_DEBUG) $(SAN) -DWT_LIBRARIES_LINKED $$(sdl2-config --cflags) $< $(BUILD)/tests/libraries.o \
	    -o $@ $$(sdl2-config --libs) $(LIBS)

$(BUILD)/check $(BUILD)/tests $(BUILD)/ref $(BUILD)/bench $(BUILD)/examples $(BUILD)/data $(BUILD)/clang-ubsan $(BUILD)/avx2 $(BUILD)/fuzz:
	@mkdir -p $@

clean:
	rm -rf $(BUILD)
