# proctex - the two commands a new user needs: `make demo` and `make test`.
# Each target installs what it needs first (scripts/install-deps.sh is a no-op when all is there).
.PHONY: all deps build test demo bench clean

PRESET ?= default
BUILD_DIR := build
PROCTEX := $(BUILD_DIR)/cli/proctex
export POCL_CACHE_DIR ?= $(CURDIR)/$(BUILD_DIR)/pocl-cache

all: build

deps:
	@scripts/install-deps.sh

build: deps
	@cmake --preset $(PRESET) >/dev/null
	@cmake --build --preset $(PRESET)

test: build
	@ctest --preset $(PRESET)

# The demo needs only the proctex binary, not every test and benchmark.
demo: deps
	@cmake --preset $(PRESET) >/dev/null
	@cmake --build --preset $(PRESET) --target proctex
	@scripts/demo.sh $(PROCTEX)

bench: build
	@scripts/install-deps.sh --with-bench
	@scripts/bench.sh $(BUILD_DIR)

clean:
	rm -rf $(BUILD_DIR) build-debug
