# idyvins: the two commands a newcomer needs are `make demo` and `make test`.
BUILD ?= build
JOBS  ?= 2
# A unity build (8 sources per translation unit): a third less compile time, byte-identical outputs
# (docs/ci.md); CMAKE_FLAGS="-DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=OFF" for one object per source.
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release -DIDYVINS_WERROR=ON -DCMAKE_UNITY_BUILD=ON
# Each step's seconds go to $IDYVINS_TIMES when it is set (.ci/run's table).
TIMED = $(CURDIR)/scripts/timed.sh

.PHONY: all setup build demo test sanitize bench fuzz clean

all: build

setup:
	$(TIMED) "setup (scripts/setup.sh)" ./scripts/setup.sh

build: setup
	$(TIMED) "configure" cmake -S . -B $(BUILD) $(CMAKE_FLAGS)
	$(TIMED) "build (Release)" cmake --build $(BUILD) -j$(JOBS)

demo: build
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
