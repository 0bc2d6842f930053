# vismask build. `make` builds build/vismask; `make demo` and `make test` first
# install what is missing (tools/install-deps), so on a fresh Debian 12 machine
# they are the whole set-up.
#   make SAN=1 test     the suite under ASan + UBSan
#   make CROSS=aarch64-linux-gnu-   cross build (see docs/DEPLOY.md)

CROSS ?=
CXX := $(CROSS)g++
BUILD ?= build
SAN ?= 0

CXXFLAGS := -std=c++17 -O2 -Wall -Wextra -Werror -ffp-contract=off -fno-plt \
            -Iinclude -Iplatform -I/usr/include/stb -MMD -MP
LDLIBS := -lz
ifeq ($(SAN),1)
  BUILD := $(BUILD)/san
  CXXFLAGS += -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g
  LDFLAGS += -fsanitize=address,undefined
endif

LIB_SRC := $(wildcard src/*.cpp) $(wildcard platform/*.cpp)
LIB_SRC := $(filter-out src/main.cpp,$(LIB_SRC))
LIB_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(LIB_SRC))
TEST_SRC := $(wildcard tests/*.cpp)
TEST_OBJ := $(patsubst %.cpp,$(BUILD)/obj/%.o,$(TEST_SRC))
HEADERS := $(wildcard include/vismask/*.h)

.PHONY: all deps demo test headers clean
all: $(BUILD)/vismask

deps:
	@tools/install-deps

$(BUILD)/obj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS) -c $< -o $@

$(BUILD)/vismask: $(BUILD)/obj/src/main.o $(LIB_OBJ)
	$(CXX) $(LDFLAGS) $^ -o $@ $(LDLIBS)

$(BUILD)/vismask_tests: $(TEST_OBJ) $(LIB_OBJ)
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
	$(MAKE) headers $(BUILD)/vismask $(BUILD)/vismask_tests
	VISMASK_BIN=$(BUILD)/vismask $(BUILD)/vismask_tests

clean:
	rm -rf build out

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
