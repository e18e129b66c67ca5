# Four single-header libraries, their tests, benchmarks and examples.
#
#   make          build the examples
#   make test     install the reference libraries if needed, compile-check every
#                 header, run unit tests (ASan+UBSan) and reference tests
#   make bench    run the benchmarks (throughput next to the papers' figures)
#   make demo     run the main example
#   make clean
#
# Files are found by name, so adding one needs no edit here:
#   tests/test_*.c    unit tests: headers only, run under ASan+UBSan
#   tests/tsan_*.c    concurrency tests: headers only, run under ThreadSanitizer
#   tests/ref_*.c     reference tests: linked with tests/reference (Embree, OpenEXR)
#   tests/bench_*.c   benchmarks: optimised, linked with tests/reference
#   examples/*.c      examples: one program each, `cc examples/x.c -lm` builds it
#   tests/check_*.py  checks of the generated data (python3), run by make test
#   tests/assimp_*.c  unit tests that need Assimp: built and run only when it is present

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
LIBS    := -lm -lpthread
OPT     := -O2
BENCH_OPT ?= -O3 -march=native

# Every program depends on every project header: headers are the product.
ALL_H := $(HEADERS) $(wildcard tests/*.h tests/reference/*.h examples/common/*.h)

UNIT_BINS    := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/test_*.c))
TSAN_BINS    := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/tsan_*.c))
REF_BINS     := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/ref_*.c))
BENCH_BINS   := $(patsubst tests/%.c,$(BUILD)/bench/%,$(wildcard tests/bench_*.c))
EXAMPLE_BINS := $(patsubst examples/%.c,$(BUILD)/examples/%,$(wildcard examples/*.c))
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

# The reference libraries are looked up only after tests/deps.sh ran.
REF_CFLAGS = $(shell pkg-config --cflags OpenEXR 2>/dev/null)
REF_LIBS   = -lembree3 $(shell pkg-config --libs OpenEXR 2>/dev/null)

.SECONDARY:
.PHONY: all examples test test-build test-run bench bench-build demo deps clean

all: examples
examples: $(EXAMPLE_BINS)

test: deps
	@$(MAKE) --no-print-directory -j$(NPROC) test-build
	@$(MAKE) --no-print-directory test-run

# A make of its own after deps: Assimp may just have been installed.
test-run:
	@tests/run.sh $(DATA_CHECKS) $(LINKAGE_BIN) $(UNIT_BINS) $(TSAN_BINS) $(REF_BINS) $(ASSIMP_BINS)

test-build: $(CHECK_OBJS) $(LINKAGE_BIN) $(UNIT_BINS) $(TSAN_BINS) $(REF_BINS) $(ASSIMP_BINS) $(EXAMPLE_BINS)

bench: deps
	@$(MAKE) --no-print-directory -j$(NPROC) bench-build $(BUILDINGS)
	@for b in $(BENCH_BINS); do echo "== $$(basename $$b)"; $$b || exit 1; done

bench-build: $(BENCH_BINS)

# The main job. Runs the walkthrough once it exists, else the scene viewer.
DEMO := $(if $(wildcard examples/walkthrough.c),$(BUILD)/examples/walkthrough,$(BUILD)/examples/scene_view)
demo: $(DEMO)
	@mkdir -p $(BUILD)/demo
	$(DEMO) --out $(BUILD)/demo

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

# --- tests ----------------------------------------------------------------
$(LINKAGE_BIN): tests/linkage/impl.c tests/linkage/main.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) $(OPT) tests/linkage/impl.c tests/linkage/main.c -o $@ $(LIBS)

$(BUILD)/tests/test_%: tests/test_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 -g $(SAN) $< -o $@ $(LIBS)

$(BUILD)/tests/assimp_%: tests/assimp_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 -g $(SAN) $(ASSIMP_FLAGS) $< -o $@ $(LIBS) $(ASSIMP_LIBS)

$(BUILD)/tests/tsan_%: tests/tsan_%.c $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) -O1 -g -fsanitize=thread $< -o $@ $(LIBS)

$(BUILD)/tests/ref_%: tests/ref_%.c $(REF_OBJS) $(ALL_H) | $(BUILD)/tests
	$(CC) $(CFLAGS_PROJECT) $(OPT) -g $(REF_CFLAGS) $< $(REF_OBJS) -o $@ $(REF_LIBS) $(LIBS)

# C11: OpenEXR's C API uses anonymous unions.
$(BUILD)/ref/%.o: tests/reference/%.c $(ALL_H) | $(BUILD)/ref
	$(CC) -std=c11 $(WARN) -I. $(OPT) -g $(REF_CFLAGS) -c $< -o $@

$(BUILD)/bench/bench_%: tests/bench_%.c $(REF_OBJS) $(ALL_H) | $(BUILD)/bench
	$(CC) $(CFLAGS_PROJECT) $(BENCH_OPT) $(REF_CFLAGS) $< $(REF_OBJS) -o $@ $(REF_LIBS) $(LIBS)

$(BUILD)/data/building_%.obj: examples/data/make_building.py | $(BUILD)/data
	python3 examples/data/make_building.py --preset $* --out $(BUILD)/data/building_$*

# --- examples -------------------------------------------------------------
$(BUILD)/examples/%: examples/%.c $(ALL_H) $(ASSIMP_STAMP) | $(BUILD)/examples
	$(CC) $(CFLAGS_PROJECT) $(OPT) $(ASSIMP_FLAGS) $< -o $@ $(LIBS) $(ASSIMP_LIBS)

$(BUILD)/check $(BUILD)/tests $(BUILD)/ref $(BUILD)/bench $(BUILD)/examples $(BUILD)/data:
	@mkdir -p $@

clean:
	rm -rf $(BUILD)
