# ampath — plain GNU make. Targets: all (default), check, demo, bench, cross, fuzz, fuzz-selftest,
# install, uninstall, clean. Honours CC, CFLAGS, LDFLAGS, PREFIX, DESTDIR, OPENMP=0.
#
# Sources are found by name, so a new module needs no edit here:
#   lib/*.c              -> lib/libampath.a and lib/libampath.so
#   tools/*.c            -> tools/ampath (tools/cmd_NAME.c = command NAME, tools/bench_NAME.c = benchmark NAME)
#   tools/vprinter/*.c   -> tools/ampath-vprinter (virtual printer)
#   bridge/*.c           -> bridge/ampath-bridge (bridge/main.c holds main; the rest is also linked into tests)
#   tests/test_*.c       -> one Check program each; other tests/*.c are shared fixtures
#   tests/fuzz/fuzz_*.c  -> libFuzzer targets (make fuzz)

VERSION := $(shell sed -n 's/^\#define AMP_VERSION_STRING "\(.*\)"/\1/p' include/ampath/version.h)
PREFIX ?= /usr/local
BINDIR ?= $(PREFIX)/bin
LIBDIR ?= $(PREFIX)/lib
INCDIR ?= $(PREFIX)/include
MANDIR ?= $(PREFIX)/share/man
OPENMP ?= 1
CFLAGS ?= -O2 -g
SAN ?= 0
V ?= 0
ifeq ($(V),1)
Q :=
else
Q := @
endif

# Build directory: the plain build in build/, the sanitizer build in build/san.
ifeq ($(SAN),1)
B := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
OUTLIB := $(B)
OUTBIN := $(B)
else
B := build
SANFLAGS :=
OUTLIB := lib
OUTBIN := .
endif

# -Werror only where we promise a clean build (make check, CI): a user's newer
# compiler with new warnings still builds the library.
WERROR ?= 0
WARN := -std=c99 -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes $(if $(filter 1,$(WERROR)),-Werror)
ifeq ($(OPENMP),1)
OMP := -fopenmp
else
OMP := -Wno-unknown-pragmas
endif
ALL_CFLAGS := $(WARN) $(OMP) $(SANFLAGS) -Iinclude -MMD -MP $(CFLAGS)
ALL_LDFLAGS := $(OMP) $(SANFLAGS) $(LDFLAGS)

LIB_SRC := $(sort $(wildcard lib/*.c))
TOOL_SRC := $(sort $(wildcard tools/*.c))
VPR_SRC := $(sort $(wildcard tools/vprinter/*.c))
BRIDGE_SRC := $(sort $(wildcard bridge/*.c))
# main.c and bench.c (`ampath-bridge --bench`, which uses tools/cli.c) make the program; the rest is the
# bridge core the tests link too
BRIDGE_MAIN := $(filter bridge/main.c bridge/bench.c,$(BRIDGE_SRC))
BRIDGE_CORE := $(filter-out bridge/main.c bridge/bench.c,$(BRIDGE_SRC))
TEST_SRC := $(sort $(wildcard tests/test_*.c))
FIXTURE_SRC := $(filter-out $(TEST_SRC),$(sort $(wildcard tests/*.c)))
CMD_NAMES := $(patsubst tools/cmd_%.c,%,$(sort $(wildcard tools/cmd_*.c)))
BENCH_NAMES := $(patsubst tools/bench_%.c,%,$(sort $(wildcard tools/bench_*.c)))

LIB_OBJ := $(LIB_SRC:%.c=$(B)/%.o)
PIC_OBJ := $(LIB_SRC:%.c=$(B)/pic/%.o)
TOOL_OBJ := $(TOOL_SRC:%.c=$(B)/%.o)
VPR_OBJ := $(VPR_SRC:%.c=$(B)/%.o)
BRIDGE_CORE_OBJ := $(BRIDGE_CORE:%.c=$(B)/%.o)
BRIDGE_MAIN_OBJ := $(BRIDGE_MAIN:%.c=$(B)/%.o)
FIXTURE_OBJ := $(FIXTURE_SRC:%.c=$(B)/%.o)
TEST_BIN := $(TEST_SRC:tests/%.c=$(B)/tests/%)
# tests/run.sh runs the programs side by side (one more than the processors: test_bridge mostly waits on
# its printers), started in this order: the longest first, so that the suite's wall time is about its
# total over the processors; the Python binding's tests (plain build) go first of all
TEST_SLOW := $(addprefix $(B)/tests/,test_field test_bridge test_contpath test_gcode test_slice test_order)
TEST_RUN := $(filter $(TEST_SLOW),$(TEST_BIN)) $(filter-out $(TEST_SLOW),$(TEST_BIN))

LIBA := $(OUTLIB)/libampath.a
LIBSO := $(OUTLIB)/libampath.so
AMPATH := $(OUTBIN)/tools/ampath
VPRINTER := $(if $(VPR_SRC),$(OUTBIN)/tools/ampath-vprinter)
BRIDGE := $(if $(filter bridge/main.c,$(BRIDGE_MAIN)),$(OUTBIN)/bridge/ampath-bridge)

SERIAL_CFLAGS = $(shell pkg-config --cflags libserialport 2>/dev/null)
SERIAL_LIBS = $(shell pkg-config --libs libserialport 2>/dev/null || echo -lserialport)
CHECK_CFLAGS = $(shell pkg-config --cflags check 2>/dev/null)
CHECK_LIBS = $(shell pkg-config --libs check 2>/dev/null || echo -lcheck -lsubunit -lrt -lpthread)

BUILD_PKGS := gcc make pkg-config libserialport-dev
TEST_PKGS := $(BUILD_PKGS) check python3
CROSS_PKGS := gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi
FUZZ_PKGS := clang libclang-rt-14-dev
# make bench only: PrusaSlicer for the side-by-side of `bench slice` (skipped when it cannot be installed)
BENCH_PKGS := prusa-slicer

.PHONY: all check test-run demo bench soak cross fuzz fuzz-selftest install uninstall clean deps-present deps-build deps-test FORCE
.DELETE_ON_ERROR:
.SECONDARY:

all: deps-present $(LIBA) $(LIBSO) $(AMPATH) $(VPRINTER) $(BRIDGE)

# A plain build never installs anything: it names what is missing and stops.
# make check, demo and cross install their packages (SPEC §1).
deps-present:
	@sh tools/deps.sh --check $(BUILD_PKGS)
deps-build:
	@sh tools/deps.sh $(BUILD_PKGS)
deps-test:
	@sh tools/deps.sh $(TEST_PKGS)

# Objects depend on the flags they were built with, so that make check's
# -Werror (or SAN, OPENMP) rebuilds what a plain make built.
$(B)/gen/cflags: FORCE
	@mkdir -p $(dir $@)
	@echo '$(ALL_CFLAGS)' > $@.tmp
	@cmp -s $@.tmp $@ || mv $@.tmp $@; rm -f $@.tmp

# ---- library ----
$(B)/%.o: %.c $(B)/gen/cflags
	@mkdir -p $(dir $@)
	@echo '  CC      $<'
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(B)/pic/%.o: %.c $(B)/gen/cflags
	@mkdir -p $(dir $@)
	$(Q)$(CC) $(ALL_CFLAGS) -fPIC -c $< -o $@

$(LIBA): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	@echo '  AR      $@'
	$(Q)rm -f $@
	$(Q)$(AR) rcs $@ $^

# The shared library exports exactly the functions of the public headers (as
# libserialport does with its visibility attribute): internal amp_ helpers stay local.
$(B)/gen/libampath.map: $(sort $(wildcard include/ampath/*.h)) tools/exports.sh
	@mkdir -p $(dir $@)
	$(Q){ echo '{ global:'; sh tools/exports.sh include/ampath | sed 's/$$/;/'; echo 'local: *; };'; } > $@

$(LIBSO): $(PIC_OBJ) $(B)/gen/libampath.map
	@mkdir -p $(dir $@)
	@echo '  LD      $@'
	$(Q)$(CC) -shared -Wl,-soname,libampath.so.0 -Wl,--version-script=$(B)/gen/libampath.map $(ALL_LDFLAGS) \
		$(PIC_OBJ) -o $@ -lm

# ---- tools/ampath: commands and benchmarks are registered by file name ----
$(B)/gen/commands.inc: FORCE
	@mkdir -p $(dir $@)
	@printf '$(foreach c,$(CMD_NAMES),AMP_CMD($(c))\n)' > $@.tmp
	@cmp -s $@.tmp $@ || mv $@.tmp $@; rm -f $@.tmp
$(B)/gen/benches.inc: FORCE
	@mkdir -p $(dir $@)
	@printf '$(foreach c,$(BENCH_NAMES),AMP_BENCH($(c))\n)' > $@.tmp
	@cmp -s $@.tmp $@ || mv $@.tmp $@; rm -f $@.tmp

$(B)/tools/%.o: tools/%.c $(B)/gen/commands.inc $(B)/gen/benches.inc $(B)/gen/cflags
	@mkdir -p $(dir $@)
	@echo '  CC      $<'
	$(Q)$(CC) $(ALL_CFLAGS) -I$(B)/gen -Itools -c $< -o $@

# the geometry tool links neither the bridge nor libserialport
$(AMPATH): $(TOOL_OBJ) $(LIBA)
	@mkdir -p $(dir $@)
	@echo '  LD      $@'
	$(Q)$(CC) $(ALL_LDFLAGS) $(TOOL_OBJ) $(LIBA) -o $@ -lm

# the virtual printer parses its numbers as ampath does (tools/cli.c)
$(OUTBIN)/tools/ampath-vprinter: $(VPR_OBJ) $(B)/tools/cli.o $(LIBA)
	@mkdir -p $(dir $@)
	@echo '  LD      $@'
	$(Q)$(CC) $(ALL_LDFLAGS) $(VPR_OBJ) $(B)/tools/cli.o $(LIBA) -o $@ -lutil -lm

# ---- bridge ----
$(B)/bridge/%.o: bridge/%.c $(B)/gen/cflags
	@mkdir -p $(dir $@)
	@echo '  CC      $<'
	$(Q)$(CC) $(ALL_CFLAGS) -Ibridge -Itools -I$(B)/gen $(SERIAL_CFLAGS) -c $< -o $@
$(B)/bridge/bench.o: $(B)/gen/commands.inc

$(OUTBIN)/bridge/ampath-bridge: $(BRIDGE_MAIN_OBJ) $(BRIDGE_CORE_OBJ) $(B)/tools/cli.o $(LIBA)
	@mkdir -p $(dir $@)
	@echo '  LD      $@'
	$(Q)$(CC) $(ALL_LDFLAGS) $^ -o $@ $(SERIAL_LIBS) -lm

# ---- tests ----
$(B)/tests/%.o: tests/%.c $(B)/gen/cflags
	@mkdir -p $(dir $@)
	@echo '  CC      $<'
	$(Q)$(CC) $(ALL_CFLAGS) -Itests -Ibridge -Itools $(CHECK_CFLAGS) $(SERIAL_CFLAGS) -c $< -o $@

$(B)/tests/test_%: $(B)/tests/test_%.o $(FIXTURE_OBJ) $(BRIDGE_CORE_OBJ) $(LIBA)
	@echo '  LD      $@'
	$(Q)$(CC) $(ALL_LDFLAGS) $^ -o $@ $(CHECK_LIBS) $(if $(BRIDGE_CORE),$(SERIAL_LIBS)) -lm

# Tests find the programs they drive through these variables. The sanitizer run scales every test's timeout
# by 4 (CK_TIMEOUT_MULTIPLIER): ASan+UBSan code runs 2-3 times slower, more on a loaded machine (a 120 s
# skin test of test_contpath timed out beside three other jobs).
TEST_ENV := AMP_TOOL=$(abspath $(AMPATH)) AMP_VPRINTER=$(abspath $(OUTBIN)/tools/ampath-vprinter) \
	AMP_BRIDGE=$(abspath $(OUTBIN)/bridge/ampath-bridge) AMP_LIBSO=$(abspath $(LIBSO)) CK_DEFAULT_TIMEOUT=600

test-run: $(TEST_BIN) $(AMPATH) $(VPRINTER) $(BRIDGE) $(LIBSO)
	@echo "== test suite ($(if $(filter 1,$(SAN)),ASan+UBSan,plain) build)"
	@$(TEST_ENV) AMPATH_LIBRARY=$(abspath $(LIBSO)) ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
		$(if $(filter 1,$(SAN)),CK_TIMEOUT_MULTIPLIER=4) sh tests/run.sh $(if $(filter 1,$(SAN)),,python/tests/run.py) $(TEST_RUN)

# make check compiles on every processor (JOBS=N to change)
JOBS ?= $(shell getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)
CHECK_J := -j$(JOBS)

check: deps-test
	@$(MAKE) --no-print-directory $(CHECK_J) WERROR=1 all
	@$(MAKE) --no-print-directory $(CHECK_J) WERROR=1 test-run
	@$(MAKE) --no-print-directory $(CHECK_J) WERROR=1 SAN=1 OPENMP=0 test-run
	@$(MAKE) --no-print-directory $(CHECK_J) WERROR=1 cross

# ---- demo, bench ----
demo: deps-build
	@$(MAKE) --no-print-directory all
	@sh tools/demo.sh

bench: all
	@sh tools/deps.sh $(BENCH_PKGS) || echo "ampath: $(BENCH_PKGS) not installed: bench slice skips its side-by-side" >&2
	$(AMPATH) bench

# issue 10's soak at full size (10^5 moves, a few minutes): SOAK_LINES=N to change
soak: all
	@sh tools/soak.sh

# ---- cross build for Cortex-M4F: the library must compile freestanding-friendly ----
CROSS_CC ?= arm-none-eabi-gcc
CROSS_FLAGS := -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard -Os -ffunction-sections -fdata-sections
CROSS_OBJ := $(LIB_SRC:%.c=build/cross/%.o)
build/cross/%.o: %.c
	@mkdir -p $(dir $@)
	@echo '  CC(arm) $<'
	$(Q)$(CROSS_CC) $(WARN) -Wno-unknown-pragmas $(CROSS_FLAGS) -Iinclude -c $< -o $@
build/cross/libampath.a: $(CROSS_OBJ)
	$(Q)rm -f $@
	$(Q)arm-none-eabi-ar rcs $@ $^
cross:
	@sh tools/deps.sh $(CROSS_PKGS)
	@$(MAKE) --no-print-directory build/cross/libampath.a
	@arm-none-eabi-size -t build/cross/libampath.a | tail -n 1 | \
		awk '{print "cross (Cortex-M4F): libampath.a text " $$1 " B, data " $$2 " B, bss " $$3 " B"}'

# ---- fuzzing (clang libFuzzer): make fuzz FUZZ_SECONDS=60 ----
# tests/fuzz/run.sh makes a seed corpus from the built-in models with the tool, runs every
# target and fails on the first finding (crash, ASan, or UBSan: -fno-sanitize-recover).
# FUZZ_PLANT=trap|ubsan builds the targets with a planted defect (in build/fuzz-PLANT);
# `make fuzz-selftest` proves that make fuzz then fails.
FUZZ_SECONDS ?= 30
FUZZ_PLANT ?=
FUZZ_SRC := $(sort $(wildcard tests/fuzz/fuzz_*.c))
FUZZ_DIR := build/fuzz$(if $(FUZZ_PLANT),-$(FUZZ_PLANT))
FUZZ_BIN := $(FUZZ_SRC:tests/fuzz/%.c=$(FUZZ_DIR)/%)
FUZZ_FLAGS := -std=c99 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
	$(if $(FUZZ_PLANT),-DAMP_FUZZ_PLANT_$(shell echo $(FUZZ_PLANT) | tr a-z A-Z))
$(FUZZ_DIR)/%: tests/fuzz/%.c $(LIB_SRC)
	@mkdir -p $(dir $@)
	clang $(FUZZ_FLAGS) -Iinclude $< $(LIB_SRC) -o $@ -lm
fuzz: all
	@sh tools/deps.sh $(FUZZ_PKGS)
	@$(MAKE) --no-print-directory $(FUZZ_BIN)
	@sh tests/fuzz/run.sh $(abspath $(AMPATH)) $(FUZZ_SECONDS) $(FUZZ_DIR) $(FUZZ_BIN)
fuzz-selftest: all
	@MAKE="$(MAKE)" sh tests/fuzz/plant_test.sh

# ---- install ----
HEADERS := $(sort $(wildcard include/ampath/*.h))
MANPAGES := $(sort $(wildcard docs/man/*.1))
$(B)/ampath.pc: FORCE
	@mkdir -p $(dir $@)
	@printf 'prefix=$(PREFIX)\nlibdir=$(LIBDIR)\nincludedir=$(INCDIR)\n\nName: ampath\nDescription: print paths for additive manufacturing (volumetric covering, continuous tool paths)\nVersion: $(VERSION)\nLibs: -L$${libdir} -lampath\nLibs.private: -lm$(if $(filter 1,$(OPENMP)), -fopenmp)\nCflags: -I$${includedir}\n' > $@

install: all $(B)/ampath.pc
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(INCDIR)/ampath $(DESTDIR)$(MANDIR)/man1
	install -m 644 $(HEADERS) $(DESTDIR)$(INCDIR)/ampath/
	install -m 644 $(LIBA) $(DESTDIR)$(LIBDIR)/
	install -m 755 $(LIBSO) $(DESTDIR)$(LIBDIR)/libampath.so.$(VERSION)
	ln -sf libampath.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libampath.so.0
	ln -sf libampath.so.0 $(DESTDIR)$(LIBDIR)/libampath.so
	install -m 644 $(B)/ampath.pc $(DESTDIR)$(LIBDIR)/pkgconfig/
	install -m 755 $(AMPATH) $(VPRINTER) $(BRIDGE) $(DESTDIR)$(BINDIR)/
	$(if $(MANPAGES),install -m 644 $(MANPAGES) $(DESTDIR)$(MANDIR)/man1/)

uninstall:
	rm -rf $(DESTDIR)$(INCDIR)/ampath
	rm -f $(DESTDIR)$(LIBDIR)/libampath.a $(DESTDIR)$(LIBDIR)/libampath.so $(DESTDIR)$(LIBDIR)/libampath.so.0 \
		$(DESTDIR)$(LIBDIR)/libampath.so.$(VERSION) $(DESTDIR)$(LIBDIR)/pkgconfig/ampath.pc
	rm -f $(DESTDIR)$(BINDIR)/ampath $(DESTDIR)$(BINDIR)/ampath-vprinter $(DESTDIR)$(BINDIR)/ampath-bridge
	rm -f $(addprefix $(DESTDIR)$(MANDIR)/man1/,$(notdir $(MANPAGES)))

clean:
	rm -rf build lib/libampath.a lib/libampath.so tools/ampath tools/ampath-vprinter bridge/ampath-bridge demo

-include $(shell find build -name '*.d' 2>/dev/null)
