# vismask build. `make` builds build/vismask (transports loop and pipe) and,
# when mpicxx is found, build/vismask-mpi (Open MPI); `make demo` and
# `make test` first install what is missing (tools/install-deps), so on a
# fresh Debian 12 machine they are the whole set-up.
#   make SAN=1 test     the suite under ASan + UBSan (DCHECKs on)
#   make DEBUG=1 test   the suite with DCHECKs on, no sanitizers (build/debug)
#   make MPI=0          without build/vismask-mpi
#   make CROSS=aarch64-linux-gnu-   cross build into build/aarch64 (docs/DEPLOY.md)
#   make CROSS=arm-linux-gnueabihf- 32-bit ARM, into build/armhf
#   make test-cross     the aarch64 tests and a render under qemu, compared with native
#   make experiments    the paper's figures and table as numbers: docs/RESULTS.md
#   make renderpark RPK_SRC=DIR  rpkCpp (RenderPark) built from DIR, for issue 41's comparison
#   make cluster-experiments  (root) simulated Pi clusters, docs/CLUSTER.md
#   make fuzz FUZZ_SECONDS=N   libFuzzer on the scene loader and the image readers (clang)
#   make fuzz-report    10 M executions of each fuzz target: docs/STABILITY.md
#   make stability      the stiff and extreme suites: docs/STABILITY.md
#   make outside-check  --sky and --sun against Cycles on a skylight: docs/OUTSIDE.md
#   make check-sizes    source files over 450 lines and functions over 120 (tools/check-sizes)

CROSS ?=
CXX := $(CROSS)g++
BUILD ?= build
SAN ?= 0
MPI ?= 1
MPICXX ?= mpicxx

# V=1 shows the full compiler and linker lines; by default make says
# "CXX src/scene/foo.cpp" and "LD build/vismask".
V ?= 0
ifeq ($(V),1)
  Q :=
  SAY := @true
else
  Q := @
  SAY := @printf '%-4s %s\n'
endif

CXXFLAGS := -std=c++17 -O2 -Wall -Wextra -Werror -ffp-contract=off -fno-plt \
            -Iinclude -Iplatform -MMD -MP
LDLIBS := -lz -ljpeg

# Cross builds (docs/DEPLOY.md). Objects and binaries go to build/aarch64 or
# build/armhf, so the native ones are untouched. The target's zlib, GoogleTest,
# GLM and stb come from a sysroot, build/sysroot-ARCH, that
# tools/fetch-arm64-mpi fetches (apt-get download + dpkg -x, no system
# change); make runs it when the sysroot is missing.
ifeq ($(CROSS),)
  CXXFLAGS += -I/usr/include/stb
else
  TRIPLET := $(CROSS:%-=%)
  DEB_ARCH := $(or $(if $(filter aarch64-%,$(TRIPLET)),arm64), \
                   $(if $(filter arm-%hf,$(TRIPLET)),armhf), \
                   $(firstword $(subst -, ,$(TRIPLET))))
  TARGET := $(if $(filter arm64,$(DEB_ARCH)),aarch64,$(DEB_ARCH))
  ifeq ($(origin BUILD),file)
    BUILD := build/$(TARGET)
  endif
  ifeq ($(shell command -v $(CXX) 2>/dev/null),)
    $(error $(CXX) not found: tools/install-deps --cross installs the cross compilers)
  endif
  SYSROOT := build/sysroot-$(DEB_ARCH)
  SYSROOT_LIB := $(SYSROOT)/usr/lib/$(TRIPLET)
  CXXFLAGS += -I$(SYSROOT)/usr/include/stb -isystem $(SYSROOT)/usr/include \
              -isystem $(SYSROOT)/usr/include/$(TRIPLET)
  # 32-bit ARM: GCC notes that passing some structs changed ABI in GCC 7.1;
  # everything here is built by one compiler, so the note is noise.
  ifeq ($(DEB_ARCH),armhf)
    CXXFLAGS += -Wno-psabi
  endif
  LDFLAGS += -L$(SYSROOT_LIB) -Wl,-rpath-link=$(SYSROOT)/lib/$(TRIPLET):$(SYSROOT_LIB)
endif
ifeq ($(SAN),1)
  BUILD := $(BUILD)/san
  # GCC 12 gives false -Wmaybe-uninitialized inside libstdc++'s <regex>
  # (tests/viewer_test.cpp) under -fsanitize=address, and -Werror made it
  # fatal: SAN builds keep every other warning.
  CXXFLAGS += -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g \
              -Wno-maybe-uninitialized
  LDFLAGS += -fsanitize=address,undefined
endif
# DCHECK (check.h) is for hot loops: release builds drop it (NDEBUG), SAN=1
# and DEBUG=1 builds keep it. CHECK is always on.
DEBUG ?= 0
ifeq ($(DEBUG),1)
  BUILD := $(BUILD)/debug
  CXXFLAGS += -g
else ifneq ($(SAN),1)
  CXXFLAGS += -DNDEBUG
endif

# The transport is chosen by what is linked: each binary gets one of these.
TRANSPORT_SRC := platform/transport_posix.cpp platform/transport_loop.cpp platform/transport_pipe.cpp \
                 platform/transport_pipe_process.cpp platform/transport_pipe_frames.cpp \
                 platform/transport_mpi.cpp
LIB_SRC := $(wildcard src/*/*.cpp) $(wildcard platform/*.cpp)
LIB_SRC := $(filter-out src/app/main.cpp $(TRANSPORT_SRC),$(LIB_SRC))
LIB_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(LIB_SRC))
POSIX_OBJ := $(BUILD)/obj/platform/transport_posix.o $(BUILD)/obj/platform/transport_loop.o \
             $(BUILD)/obj/platform/transport_pipe.o $(BUILD)/obj/platform/transport_pipe_process.o \
             $(BUILD)/obj/platform/transport_pipe_frames.o
MPI_OBJ := $(BUILD)/obj/platform/transport_mpi.o
TEST_SRC := $(wildcard tests/*.cpp)
TEST_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(TEST_SRC))
HEADERS := $(wildcard include/vismask/*/*.h)

# MPI=1 without mpicxx (tools/install-deps installs it) builds as MPI=0.
# A cross build has no mpicxx for the target: it compiles and links against
# the target's Open MPI in the sysroot (tools/fetch-arm64-mpi), when that is
# there or when MPI=1 is given on the command line (make then fetches it);
# otherwise it builds without vismask-mpi. MPICXX=... naming a wrapper for
# the target is used instead, as before.
MPI_MODE := wrapper
ifeq ($(MPI),1)
  ifneq ($(CROSS),)
    ifeq ($(origin MPICXX),file)
      ifneq ($(wildcard $(SYSROOT)/.mpi-ok)$(filter command line,$(origin MPI)),)
        MPI_MODE := sysroot
      else
        $(info make: cross build without $(BUILD)/vismask-mpi (make CROSS=$(CROSS) MPI=1 fetches the target's Open MPI))
        override MPI := 0
      endif
    endif
  endif
  ifeq ($(MPI_MODE),wrapper)
    ifeq ($(shell command -v $(MPICXX) 2>/dev/null),)
      $(info make: $(MPICXX) not found, building without build/vismask-mpi (MPI=0))
      override MPI := 0
    endif
  endif
endif
MPI_BIN := $(if $(filter 1,$(MPI)),$(BUILD)/vismask-mpi)
MPI_INC := $(SYSROOT_LIB)/openmpi/include
MPI_LIBDIR := $(SYSROOT_LIB)/openmpi/lib

.PHONY: all deps demo demo-image test format format-check viewer view viewer-screenshot install uninstall headers clean test-cross experiments renderpark parallel cluster-experiments cluster-million cluster-resume bench fuzz fuzz-deps fuzz-report stability outside-check check-sizes
all: $(BUILD)/vismask $(MPI_BIN)

deps:
	@tools/install-deps

# A cross build needs the target's libraries before it compiles anything.
ifneq ($(CROSS),)
SYSROOT_DEP := | $(SYSROOT)/.base-ok
$(SYSROOT)/.base-ok:
	tools/fetch-arm64-mpi --arch $(DEB_ARCH) --no-mpi
$(SYSROOT)/.mpi-ok:
	tools/fetch-arm64-mpi --arch $(DEB_ARCH)
endif

$(BUILD)/obj/%.o: %.cpp $(SYSROOT_DEP)
	@mkdir -p $(dir $@)
	$(SAY) CXX $<
	$(Q)$(CXX) $(CXXFLAGS) -c $< -o $@
# stb_image 2.27, compiled into texture_decode.cpp, may overflow signed ints on
# corrupt input (it did in its JPEG DC prediction, before JPEG went to
# libjpeg-turbo): -fwrapv makes them wrap, as the hardware does, instead of
# undefined behaviour.
$(BUILD)/obj/src/scene/texture_decode.o build/fuzz/obj/src/scene/texture_decode.o: CXXFLAGS += -fwrapv
build/fuzz/obj/src/scene/texture_decode.o: FUZZ_CXXFLAGS += -fwrapv

$(BUILD)/vismask: $(BUILD)/obj/src/app/main.o $(LIB_OBJ) $(POSIX_OBJ)
	$(SAY) LD $@
	$(Q)$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS)

# Open MPI's wrapper around the same compiler (OMPI_CXX); only the mpi
# transport sees <mpi.h>, without the deprecated C++ bindings.
ifeq ($(MPI_MODE),wrapper)
$(MPI_OBJ): platform/transport_mpi.cpp
	@mkdir -p $(dir $@)
	$(SAY) CXX $<
	$(Q)OMPI_CXX=$(CXX) $(MPICXX) $(CXXFLAGS) -DOMPI_SKIP_MPICXX -c $< -o $@

$(BUILD)/vismask-mpi: $(BUILD)/obj/src/app/main.o $(LIB_OBJ) $(MPI_OBJ)
	$(SAY) LD $@
	$(Q)OMPI_CXX=$(CXX) $(MPICXX) $(LDFLAGS) $^ -o $@ $(LDLIBS)
else
# What mpicxx would add, for the target's Open MPI in the sysroot. Only libmpi
# and the Open MPI libraries it names are in the sysroot; the rest of its
# dependencies (pmix, hwloc, libevent, ...) are on the Pi, hence
# --allow-shlib-undefined.
$(MPI_OBJ): platform/transport_mpi.cpp | $(SYSROOT)/.base-ok $(SYSROOT)/.mpi-ok
	@mkdir -p $(dir $@)
	$(SAY) CXX $<
	$(Q)$(CXX) $(CXXFLAGS) -DOMPI_SKIP_MPICXX -isystem $(MPI_INC) -c $< -o $@

$(BUILD)/vismask-mpi: $(BUILD)/obj/src/app/main.o $(LIB_OBJ) $(MPI_OBJ)
	$(SAY) LD $@
	$(Q)$(CXX) $(LDFLAGS) -L$(MPI_LIBDIR) -Wl,--allow-shlib-undefined $^ -o $@ $(LDLIBS) -lmpi
endif

$(BUILD)/vismask_tests: $(TEST_OBJ) $(LIB_OBJ) $(POSIX_OBJ)
	$(SAY) LD $@
	$(Q)$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS) -lgtest -pthread

# The benchmark binary: the only one that links Embree and Google Benchmark
# (tools/install-deps --bench installs them). make bench runs it and the
# solve benchmarks and writes docs/BENCHMARKS.md (bench/run, Python on
# tools/vismask_tools; make bench QUICK=1 passes --quick: a smoke run).
BENCH_SRC := $(wildcard bench/*.cpp)
BENCH_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(BENCH_SRC))
$(BUILD)/vismask_bench: $(BENCH_OBJ) $(LIB_OBJ) $(POSIX_OBJ)
	$(SAY) LD $@
	$(Q)$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS) -lembree3 -lbenchmark -pthread

bench:
	tools/install-deps --bench
	$(MAKE) -j$$(nproc) all $(BUILD)/vismask_bench
	BUILD=$(BUILD) bench/run $(if $(filter 1,$(QUICK)),--quick)

# Every public header compiles on its own.
headers: $(patsubst include/vismask/%.h,$(BUILD)/headers/%.ok,$(HEADERS))
$(BUILD)/headers/%.ok: include/vismask/%.h $(SYSROOT_DEP)
	@mkdir -p $(dir $@)
	@echo '#include "vismask/$*.h"' | $(CXX) $(CXXFLAGS) -x c++ -fsyntax-only - && touch $@

# The viewer (viewer/, docs/DESIGN.md "The viewer"): index.html, viewer.js
# and serve.py, with the three.js files it imports copied from
# viewer/node_modules (npm ci, pinned by viewer/package-lock.json) into
# viewer/vendor/ (not committed), so that the page works offline and
# installs as it is. make view OUT=DIR serves DIR (vismask view).
VIEWER_FILES := index.html viewer.js serve.py
THREE := viewer/node_modules/three
VENDOR := viewer/vendor
VENDOR_FILES := $(VENDOR)/three.module.js $(VENDOR)/three.core.js $(VENDOR)/LICENSE \
  $(VENDOR)/addons/loaders/GLTFLoader.js $(VENDOR)/addons/controls/OrbitControls.js \
  $(VENDOR)/addons/utils/BufferGeometryUtils.js $(VENDOR)/addons/utils/SkeletonUtils.js
viewer/node_modules/.package-lock.json: viewer/package-lock.json viewer/package.json
	@command -v npm >/dev/null || { echo "make: npm not found: tools/install-deps installs it" >&2; exit 1; }
	cd viewer && npm ci --no-audit --no-fund
	@touch $@
$(THREE)/%: viewer/node_modules/.package-lock.json ;
$(VENDOR)/three.%: $(THREE)/build/three.%
	@mkdir -p $(dir $@)
	cp $< $@
$(VENDOR)/LICENSE: $(THREE)/LICENSE
	@mkdir -p $(dir $@)
	cp $< $@
$(VENDOR)/addons/%: $(THREE)/examples/jsm/%
	@mkdir -p $(dir $@)
	cp $< $@
viewer: $(VENDOR_FILES)
OUT ?= out
view: $(BUILD)/vismask viewer
	$(BUILD)/vismask view $(OUT)

# make viewer-screenshot: docs/img/viewer.png, the viewer on a Cornell
# export in headless Chromium (viewer/shoot.mjs), orbited a little by a
# mouse drag, for the README.
viewer-screenshot: $(BUILD)/vismask viewer
	@rm -rf $(BUILD)/viewer-screenshot
	$(BUILD)/vismask render scenes/cornell.obj --out $(BUILD)/viewer-screenshot \
	  --export $(BUILD)/viewer-screenshot/cornell.glb --quiet
	node viewer/shoot.mjs --vismask $(BUILD)/vismask --out $(BUILD)/viewer-screenshot \
	  --width 900 --height 600 --panel --drag -35,12 --screenshot docs/img/viewer.png

# make install PREFIX=/usr/local DESTDIR=...: the binaries in bin/, the
# viewer (with its three.js files) in share/vismask/viewer/ and a man page
# made by help2man from --help all (every row of the option table,
# options_table.h) in share/man/man1/. make uninstall removes
# them (share/vismask/ whole; bin/ and share/man/man1/ stay).
PREFIX ?= /usr/local
DESTDIR ?=
BINDIR := $(DESTDIR)$(PREFIX)/bin
SHAREDIR := $(DESTDIR)$(PREFIX)/share/vismask
MAN1DIR := $(DESTDIR)$(PREFIX)/share/man/man1
$(BUILD)/vismask.1: $(BUILD)/vismask
	@command -v help2man >/dev/null || { echo "make: help2man not found: tools/install-deps installs it" >&2; exit 1; }
	help2man --no-info --no-discard-stderr --version-string=1 --help-option="--help all" \
	  --name="fixed-memory parallel radiosity renderer" \
	  --output=$@ $(BUILD)/vismask
install: all viewer $(BUILD)/vismask.1
	install -d $(BINDIR) $(SHAREDIR)/viewer $(MAN1DIR)
	install -m 755 $(BUILD)/vismask $(MPI_BIN) $(BINDIR)/
	install -m 644 $(addprefix viewer/,$(VIEWER_FILES)) $(SHAREDIR)/viewer/
	cd viewer && for f in $(patsubst viewer/%,%,$(VENDOR_FILES)); do \
	  install -D -m 644 $$f $(abspath $(SHAREDIR))/viewer/$$f || exit 1; done
	install -m 644 $(BUILD)/vismask.1 $(MAN1DIR)/vismask.1
	$(if $(MPI_BIN),echo '.so man1/vismask.1' > $(MAN1DIR)/vismask-mpi.1 && chmod 644 $(MAN1DIR)/vismask-mpi.1)
uninstall:
	rm -f $(BINDIR)/vismask $(BINDIR)/vismask-mpi $(MAN1DIR)/vismask.1 $(MAN1DIR)/vismask-mpi.1
	rm -rf $(SHAREDIR)

demo: deps
	$(MAKE) $(BUILD)/vismask
	$(BUILD)/vismask render scenes/cornell.obj --out out

# docs/img/cornell.png, the README's picture: the demo's render (default
# options), written by this target, never by hand.
demo-image: deps
	$(MAKE) $(BUILD)/vismask
	$(BUILD)/vismask render scenes/cornell.obj --out $(BUILD)/demo-image --quiet
	cp $(BUILD)/demo-image/image.png docs/img/cornell.png

# The bench binary too, when its libraries are there (tools/install-deps
# --bench), so that make test keeps it compiling; make bench runs it.
BENCH_IF_PRESENT := $(if $(and $(wildcard /usr/include/embree3/rtcore.h),$(wildcard /usr/include/benchmark/benchmark.h)),$(BUILD)/vismask_bench)
# The viewer's three.js files too, when npm is there (tools/install-deps
# installs it), for the viewer's tests; VISMASK_MAKE_ARGS tells the install
# test which build make install should take.
VIEWER_IF_NPM := $(if $(shell command -v npm 2>/dev/null),viewer)
# make check-sizes: no .cpp or .h under src/, include/ or platform/ over 450
# lines and no function over 120 (tools/check-sizes; its --selftest first).
check-sizes:
	@tools/check-sizes --selftest && tools/check-sizes

# make format-check: every C++ file is as .clang-format lays it out
# (clang-format --dry-run -Werror; .ci/run runs it before the suite), and
# no source file is over 450 lines nor function over 120 (check-sizes);
# make format rewrites the layout.
FORMAT_FILES = $(shell git ls-files '*.cpp' '*.h' 2>/dev/null || find src include platform tests bench -name '*.cpp' -o -name '*.h')
format-check: deps
	@clang-format --dry-run -Werror $(FORMAT_FILES) && echo "format-check: $(words $(FORMAT_FILES)) C++ files as .clang-format lays them out"
	@$(MAKE) --no-print-directory check-sizes
format:
	clang-format -i $(FORMAT_FILES)

# The build uses every core (-j), and so does the suite: tools/run-tests
# runs it in TEST_JOBS GoogleTest shards at once (default: the cores; 1:
# the plain binary), then prints the shards' logs and the summed
# "N passed, N failed" line.
TEST_JOBS ?= $(shell nproc 2>/dev/null || echo 1)
test: deps
	$(MAKE) -j$(TEST_JOBS) headers all $(BUILD)/vismask_tests $(BENCH_IF_PRESENT) $(VIEWER_IF_NPM)
	@if command -v blender >/dev/null; then VISMASK_BIN=$(BUILD)/vismask tools/reference --selftest; \
	 else echo "make: blender not found: tools/reference --selftest skipped (tools/install-deps --reference)"; fi
	VISMASK_BIN=$(BUILD)/vismask VISMASK_MAKE_ARGS="BUILD=$(BUILD) SAN=$(SAN) DEBUG=$(DEBUG) MPI=$(MPI)" \
	  tools/run-tests $(BUILD)/vismask_tests $(TEST_JOBS)

# docs/RESULTS.md and docs/results/ from one run of every step in
# tools/experiments (runs under build/experiments/full; about 25 minutes on
# 2 cores, less when the Cycles references are in build/reference-cache).
# Timed runs are always rerun; the others are reused when their command line
# is unchanged (rm -rf build/experiments to start afresh). The ground truth
# (issue 15) needs blender: tools/install-deps --reference.
experiments: deps
	@tools/install-deps --reference
	$(MAKE) $(BUILD)/vismask
	VISMASK_BIN=$(BUILD)/vismask tools/experiments

# RenderPark's C++ port (issue 41): RPK_SRC=DIR, a checkout of
# github.com/OscarChavarro/rpkCpp snapshot 37e5ff4e (nothing is fetched);
# its integer-option parsing fixed in the copy, built Release into
# build/renderpark/build/rpk. Without RPK_SRC it says so and does nothing.
renderpark:
	RPK_SRC=$(RPK_SRC) tools/renderpark-build

# docs/PARALLEL.md: does splitting pay? Each split run (Cornell --ranks 2,
# the pillared room in 3x1x3, the building in 4x1x4, Cornell in 5x5x5)
# against one environment in one process with default options, side by
# side, with each run's error against a Cycles ground truth (tools/parallel;
# about 15 minutes on 2 cores; QUICK=1: the tool's own check, no document).
parallel: deps
	@tools/install-deps --reference
	$(MAKE) $(BUILD)/vismask
	VISMASK_BIN=$(BUILD)/vismask tools/parallel $(if $(filter 1,$(QUICK)),--quick)

# make test-cross (after make CROSS=aarch64-linux-gnu-; CROSS defaults to
# that): the unit tests under qemu-user, then one pipe-transport Cornell
# render natively and under qemu with the same arguments, compared byte for
# byte (and, if they differ, by relative RMSE and the largest relative
# difference in B). qemu runs the target's binaries with its libc from
# /usr/TRIPLET (the cross toolchain) and zlib and libjpeg from the sysroot. The tests run
# the real binary through VISMASK_BIN: a script that starts it under qemu
# (binfmt_misc is not needed), with no -mpi beside it, so the MPI runs are
# skipped (the host's mpirun cannot start the target's vismask-mpi).
# Left out under qemu by default (CROSS_TEST_FILTER= runs them all): the two
# long convergence tests (~20x slower under qemu: 10 minutes), the peak-RSS
# test (VmHWM is then qemu's own, translator included), and the two tests
# that make the test process a child subreaper (qemu-user 7.2 answers
# prctl(PR_SET_CHILD_SUBREAPER) with EINVAL), and the install and browser
# tests (they install and serve the native binary's files).
CROSS_TEST_FILTER ?= -InstallTest.*:ViewerBrowserTest.*:EnvTest.ClosedBoxInEightEnvironmentsConverges:EnvTest.MethodALeaksLightAtHighResolutionAndBDoesNot:FootprintTest.PeakRssIsExplainedByArenasAndMappedFiles:TransportTest.PipeSurvivorsExitWhenAChildIsKilled:TransportTest.PipeChildrenExitWhenRankZeroIsKilled
CROSS_ARGS := render scenes/cornell.obj --envs 2 --ranks 2 --rays 512 --max-shots 2000 \
              --patch-size 50 --width 128 --height 128 --quiet
ifeq ($(CROSS),)
test-cross:
	tools/install-deps --cross
	$(MAKE) CROSS=aarch64-linux-gnu- test-cross
else
QEMU_ARCH := $(if $(filter arm64,$(DEB_ARCH)),aarch64,$(if $(filter armhf,$(DEB_ARCH)),arm,$(DEB_ARCH)))
QEMU := qemu-$(QEMU_ARCH)-static
QEMU_RUN := $(QEMU) -L /usr/$(TRIPLET) -E LD_LIBRARY_PATH=$(abspath $(SYSROOT))/lib/$(TRIPLET):$(abspath $(SYSROOT))/usr/lib/$(TRIPLET)
CROSS_OUT := $(BUILD)/test-cross

$(BUILD)/qemu/vismask: $(BUILD)/vismask
	@mkdir -p $(dir $@)
	printf '#!/bin/sh\nexec %s %s "$$@"\n' '$(QEMU_RUN)' '$(abspath $<)' > $@
	chmod +x $@

test-cross:
	@command -v $(QEMU) >/dev/null || { echo "make: $(QEMU) not found: tools/install-deps --cross" >&2; exit 1; }
	$(MAKE) $(BUILD)/vismask $(BUILD)/vismask_tests $(BUILD)/qemu/vismask
	$(MAKE) CROSS= build/vismask
	VISMASK_BIN=$(BUILD)/qemu/vismask $(QEMU_RUN) $(BUILD)/vismask_tests \
	  $(if $(CROSS_TEST_FILTER),'--gtest_filter=$(CROSS_TEST_FILTER)')
	@rm -rf $(CROSS_OUT) && mkdir -p $(CROSS_OUT)
	build/vismask $(CROSS_ARGS) --out $(CROSS_OUT)/native
	$(QEMU_RUN) $(BUILD)/vismask $(CROSS_ARGS) --out $(CROSS_OUT)/qemu
	@same=1; for f in image.pfm patches.csv; do \
	  if cmp -s $(CROSS_OUT)/native/$$f $(CROSS_OUT)/qemu/$$f; then \
	    echo "test-cross: $$f: bit-identical, native x86-64 and $(TARGET) under qemu"; \
	  else echo "test-cross: $$f: DIFFERS between native and $(TARGET) under qemu"; same=0; fi; \
	done; \
	if [ $$same = 0 ]; then \
	  build/vismask compare $(CROSS_OUT)/qemu/image.pfm $(CROSS_OUT)/native/image.pfm; \
	  paste -d, $(CROSS_OUT)/native/patches.csv $(CROSS_OUT)/qemu/patches.csv | awk -F, \
	    'NR > 1 { n = NF / 2; for (i = n - 2; i <= n; ++i) { a = $$i; b = $$(i + n); \
	      d = a - b; if (d < 0) d = -d; m = (a < 0 ? -a : a); if (m > 0 && d / m > r) r = d / m; } } \
	     END { printf "test-cross: largest relative difference in B (patches.csv): %g\n", r }'; \
	  exit 1; \
	fi
endif

# make cluster-experiments (root; not part of make test): vismask-mpi on 2..16
# simulated boards (tools/cluster-sim: network namespaces, tc-shaped links,
# the real mpirun), writes docs/CLUSTER.md and docs/img/cluster-time.png.
# build/mpi-wait.so is a PMPI shim that times each rank's MPI calls.
$(BUILD)/mpi-wait.so: tools/mpi-wait.c
	@mkdir -p $(dir $@)
	mpicc -O2 -Wall -Wextra -Werror -shared -fPIC $< -o $@

cluster-experiments:
	tools/install-deps --cluster
	$(MAKE) all $(BUILD)/mpi-wait.so
	tools/cluster-experiments

# The million-patch case alone (issue 20; part of cluster-experiments too):
# rewrites only its section of docs/CLUSTER.md.
cluster-million:
	tools/install-deps --cluster
	$(MAKE) all $(BUILD)/mpi-wait.so
	tools/cluster-experiments --million-only

# The lost-node case alone (issue 43; part of cluster-experiments too): 16
# nodes, one killed mid-solve, resumed on 15 from its checkpoint; rewrites
# only its section of docs/CLUSTER.md.
cluster-resume:
	tools/install-deps --cluster
	$(MAKE) all $(BUILD)/mpi-wait.so
	tools/cluster-experiments --resume-only

# libFuzzer with ASan + UBSan (clang: tools/install-deps --fuzz; tests/fuzz/):
# build/fuzz/scene_fuzz, the OBJ/MTL loader (seeds tests/fuzz/corpus),
# build/fuzz/image_fuzz, the PFM and PGM readers (seeds
# tests/fuzz/image-corpus), and build/fuzz/texture_fuzz, the texture reader
# (stb_image through vismask's checks; seeds tests/fuzz/texture-corpus), and
# build/fuzz/sky_fuzz, the --sky FILE.hdr reader (stb_image's Radiance HDR
# decoder through vismask's checks; seeds tests/fuzz/sky-corpus).
# make fuzz runs each for FUZZ_SECONDS (or FUZZ_RUNS executions, when given), one after the other; new inputs go to
# build/fuzz/corpus-TARGET, a crash to build/fuzz/TARGET-crash-* (and make
# fails). The targets link the library's objects compiled by clang with
# coverage, from an archive (build/fuzz/libvismask.a), so each takes what
# its entry point needs and no list of sources has to follow the loader.
# make fuzz-report runs each for FUZZ_REPORT_RUNS executions from its seeds
# and writes the figures into docs/STABILITY.md (tools/fuzz-report);
# FUZZ_REPORT_SECONDS=S stops each earlier, and the report says so.
FUZZ_SECONDS ?= 30
FUZZ_RUNS ?=
FUZZ_REPORT_RUNS ?= 10000000
FUZZ_REPORT_SECONDS ?=
FUZZ_CXX ?= clang++
FUZZ_TARGETS := scene image texture sky
FUZZ_BIN := $(patsubst %,build/fuzz/%_fuzz,$(FUZZ_TARGETS))
FUZZ_CXXFLAGS := -std=c++17 -O1 -g -Wall -Wextra -fsanitize=address,undefined -fno-sanitize-recover=undefined \
                 -Iinclude -Iplatform -I/usr/include/stb -MMD -MP
FUZZ_OBJ := $(patsubst %.cpp,build/fuzz/obj/%.o,$(LIB_SRC))
FUZZ_LIMIT := $(if $(FUZZ_RUNS),-runs=$(FUZZ_RUNS),-max_total_time=$(FUZZ_SECONDS))
# The options tools/fuzz-report uses too (it reads them from here).
FUZZ_OPTIONS := -max_len=8192 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
export FUZZ_OPTIONS

build/fuzz/obj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(FUZZ_CXX) $(FUZZ_CXXFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@
build/fuzz/libvismask.a: $(FUZZ_OBJ)
	@rm -f $@
	ar rcs $@ $^
build/fuzz/%_fuzz: build/fuzz/obj/tests/fuzz/%_fuzz.o build/fuzz/libvismask.a
	$(FUZZ_CXX) -fsanitize=fuzzer,address,undefined $^ -o $@ $(LDLIBS)

fuzz-deps:
	@tools/install-deps --fuzz
fuzz: fuzz-deps
	$(MAKE) $(FUZZ_BIN)
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p build/fuzz/corpus-$$t; \
	  seeds=tests/fuzz/corpus; [ $$t = scene ] || seeds=tests/fuzz/$$t-corpus; \
	  echo "build/fuzz/$${t}_fuzz build/fuzz/corpus-$$t $$seeds $(FUZZ_LIMIT) $(FUZZ_OPTIONS) -artifact_prefix=build/fuzz/$$t-"; \
	  build/fuzz/$${t}_fuzz build/fuzz/corpus-$$t $$seeds $(FUZZ_LIMIT) $(FUZZ_OPTIONS) \
	    -artifact_prefix=build/fuzz/$$t- || exit 1; \
	done
fuzz-report: fuzz-deps
	$(MAKE) $(FUZZ_BIN)
	FUZZ_RUNS=$(FUZZ_REPORT_RUNS) FUZZ_MAX_SECONDS=$(FUZZ_REPORT_SECONDS) tools/fuzz-report $(FUZZ_TARGETS)

# docs/STABILITY.md and docs/stability/ from one run of the stiff and extreme
# suites (tools/stability; 2 to 5 minutes on 2 shared cores).
stability: deps
	$(MAKE) $(BUILD)/vismask
	VISMASK_BIN=$(BUILD)/vismask tools/stability

# docs/OUTSIDE.md: --sky and --sun against Cycles on scenes/skylight.obj
# (tools/outside-check; about 5 minutes, the Cycles renders cached).
outside-check: deps
	$(MAKE) $(BUILD)/vismask
	VISMASK_BIN=$(BUILD)/vismask tools/outside-check

clean:
	rm -rf build out

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
-include $(shell find build/fuzz/obj -name '*.d' 2>/dev/null)
