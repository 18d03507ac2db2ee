# idyvins: the two commands a newcomer needs are `make demo` and `make test`.
BUILD ?= build
JOBS  ?= 2
# A unity build (8 sources per translation unit): a third less compile time, byte-identical outputs
# (docs/ci.md); CMAKE_FLAGS="-DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=OFF" for one object per source.
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release -DIDYVINS_WERROR=ON -DCMAKE_UNITY_BUILD=ON
# Each step's seconds go to $IDYVINS_TIMES when it is set (.ci/run's table).
TIMED = $(CURDIR)/scripts/timed.sh

# `make demo` installs and builds only what the demo runs (the idyvins command; a first configure
# leaves the tests, benchmarks and the ROS node out); `make build` / `make test` everything.
EVERYTHING = -DIDYVINS_BUILD_TESTS=ON -DIDYVINS_BUILD_BENCH=ON -DIDYVINS_BUILD_ROS=ON
COMMAND_ONLY = -DIDYVINS_BUILD_TESTS=OFF -DIDYVINS_BUILD_BENCH=OFF -DIDYVINS_BUILD_ROS=OFF

.PHONY: all setup setup-demo build build-demo demo test sanitize bench fuzz clean

all: build

setup:
	$(TIMED) "setup (scripts/setup.sh)" ./scripts/setup.sh

setup-demo:
	$(TIMED) "setup (scripts/setup.sh demo)" ./scripts/setup.sh demo

build: setup
	$(TIMED) "configure" cmake -S . -B $(BUILD) $(CMAKE_FLAGS) $(EVERYTHING)
	$(TIMED) "build (Release)" cmake --build $(BUILD) -j$(JOBS)

# An existing build folder keeps its configuration (a `make build` before stays whole).
build-demo: setup-demo
	@if [ ! -f $(BUILD)/CMakeCache.txt ]; then \
	  $(TIMED) "configure (the command only)" cmake -S . -B $(BUILD) $(CMAKE_FLAGS) $(COMMAND_ONLY); fi
	$(TIMED) "build (Release, the command)" cmake --build $(BUILD) -j$(JOBS) --target idyvins

demo: build-demo
	$(TIMED) "demo (scripts/demo.sh)" ./scripts/demo.sh $(BUILD)

test: build
	cd $(BUILD) && $(TIMED) "tests (ctest -j$(JOBS))" ctest --output-on-failure -j$(JOBS)

sanitize: setup
	./scripts/sanitize.sh $(BUILD)-asan

bench: build
	./scripts/bench.sh $(BUILD)

fuzz: setup
	./scripts/fuzz.sh $(BUILD)-fuzz

clean:
	rm -rf $(BUILD)
