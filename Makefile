# vismask build. `make` builds build/vismask (transports loop and pipe) and,
# when mpicxx is found, build/vismask-mpi (Open MPI); `make demo` and
# `make test` first install what is missing (tools/install-deps), so on a
# fresh Debian 12 machine they are the whole set-up.
#   make SAN=1 test     the suite under ASan + UBSan
#   make MPI=0          without build/vismask-mpi
#   make CROSS=aarch64-linux-gnu-   cross build (see docs/DEPLOY.md)

CROSS ?=
CXX := $(CROSS)g++
BUILD ?= build
SAN ?= 0
MPI ?= 1
MPICXX ?= mpicxx

CXXFLAGS := -std=c++17 -O2 -Wall -Wextra -Werror -ffp-contract=off -fno-plt \
            -Iinclude -Iplatform -I/usr/include/stb -MMD -MP
LDLIBS := -lz
ifeq ($(SAN),1)
  BUILD := $(BUILD)/san
  CXXFLAGS += -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g
  LDFLAGS += -fsanitize=address,undefined
endif

# The transport is chosen by what is linked: each binary gets one of these.
TRANSPORT_SRC := platform/transport_posix.cpp platform/transport_mpi.cpp
LIB_SRC := $(wildcard src/*.cpp) $(wildcard platform/*.cpp)
LIB_SRC := $(filter-out src/main.cpp $(TRANSPORT_SRC),$(LIB_SRC))
LIB_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(LIB_SRC))
POSIX_OBJ := $(BUILD)/obj/platform/transport_posix.o
MPI_OBJ := $(BUILD)/obj/platform/transport_mpi.o
TEST_SRC := $(wildcard tests/*.cpp)
TEST_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(TEST_SRC))
HEADERS := $(wildcard include/vismask/*.h)

# MPI=1 without mpicxx (tools/install-deps installs it) builds as MPI=0; so
# does a cross build, unless MPICXX names a wrapper for the target.
ifeq ($(MPI),1)
  ifeq ($(shell command -v $(MPICXX) 2>/dev/null),)
    $(info make: $(MPICXX) not found, building without build/vismask-mpi (MPI=0))
    override MPI := 0
  else ifneq ($(CROSS),)
    ifeq ($(origin MPICXX),file)
      $(info make: cross build, building without build/vismask-mpi (set MPICXX for the target))
      override MPI := 0
    endif
  endif
endif
MPI_BIN := $(if $(filter 1,$(MPI)),$(BUILD)/vismask-mpi)

.PHONY: all deps demo test headers clean
all: $(BUILD)/vismask $(MPI_BIN)

deps:
	@tools/install-deps

$(BUILD)/obj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS) -c $< -o $@

$(BUILD)/vismask: $(BUILD)/obj/src/main.o $(LIB_OBJ) $(POSIX_OBJ)
	$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS)

# Open MPI's wrapper around the same compiler (OMPI_CXX); only the mpi
# transport sees <mpi.h>, without the deprecated C++ bindings.
$(MPI_OBJ): platform/transport_mpi.cpp
	@mkdir -p $(dir $@)
	OMPI_CXX=$(CXX) $(MPICXX) $(CXXFLAGS) -DOMPI_SKIP_MPICXX -c $< -o $@

$(BUILD)/vismask-mpi: $(BUILD)/obj/src/main.o $(LIB_OBJ) $(MPI_OBJ)
	OMPI_CXX=$(CXX) $(MPICXX) $(LDFLAGS) $^ -o $@ $(LDLIBS)

$(BUILD)/vismask_tests: $(TEST_OBJ) $(LIB_OBJ) $(POSIX_OBJ)
	$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS) -lgtest -pthread

# Every public header compiles on its own.
headers: $(patsubst include/vismask/%.h,$(BUILD)/headers/%.ok,$(HEADERS))
$(BUILD)/headers/%.ok: include/vismask/%.h
	@mkdir -p $(dir $@)
	@echo '#include "vismask/$*.h"' | $(CXX) $(CXXFLAGS) -x c++ -fsyntax-only - && touch $@

demo: deps
	$(MAKE) $(BUILD)/vismask
	$(BUILD)/vismask render scenes/cornell.obj --out out

test: deps
	$(MAKE) headers all $(BUILD)/vismask_tests
	VISMASK_BIN=$(BUILD)/vismask $(BUILD)/vismask_tests

clean:
	rm -rf build out

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
