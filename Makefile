# idyvins: the two commands a newcomer needs are `make demo` and `make test`.
BUILD ?= build
JOBS  ?= 2
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release -DIDYVINS_WERROR=ON

.PHONY: all setup build demo test sanitize bench fuzz clean

all: build

setup:
	./scripts/setup.sh

build: setup
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)
	cmake --build $(BUILD) -j$(JOBS)

demo: build
	./scripts/demo.sh $(BUILD)

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

sanitize: setup
	./scripts/sanitize.sh $(BUILD)-asan

bench: build
	./scripts/bench.sh $(BUILD)

fuzz: setup
	./scripts/fuzz.sh $(BUILD)-fuzz

clean:
	rm -rf $(BUILD)
