# Quadrix: `make demo` and `make test` do all the set-up on a fresh Debian 12 machine.
BUILD      ?= build
SAN_BUILD  ?= build-sanitize
JOBS       ?= 2
CMAKE_ARGS ?=
DEMO_OUT   ?= out/demo
QUADRIX    := $(BUILD)/tools/quadrix

.PHONY: all deps configure build test test-sanitize demo bench fuzz clean

all: build

deps:
	@tools/setup.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j$(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) --timeout 1500

# ASan + UBSan on a fast subset: the core suites (I/O kit and readers, the checked-in malformed corpus
# through them, limits, math, reference, implicits), run directly (no CLI binary, no GL, no CGAL): the
# code every command goes through. Deterministic (fixed seeds, no fuzzing); CI runs it after `make
# test` (.ci/run), in its own build folder: about 1,000 s of CPU cold, 30 s warm.
SAN_TESTS ?= test_core_math test_core_io test_core_reference test_core_implicit test_malformed_corpus
test-sanitize: deps
	cmake -S . -B $(SAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQUADRIX_SANITIZE=ON -DQUADRIX_BENCHMARKS=OFF $(CMAKE_ARGS)
	cmake --build $(SAN_BUILD) -j$(JOBS) --target $(SAN_TESTS)
	cd $(SAN_BUILD)/tests && for t in $(SAN_TESTS); do \
	  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ./$$t --gtest_brief=1 || exit 1; done

demo: build
	@tools/demo.sh $(QUADRIX) $(DEMO_OUT)

bench: build
	@tools/bench.sh $(QUADRIX) out/bench

# libFuzzer (clang, ASan + UBSan) on the I/O kit's readers, FUZZ_SECONDS each from the malformed corpus.
FUZZ_SECONDS ?= 20
fuzz:
	@tools/fuzz.sh out/fuzz $(FUZZ_SECONDS)

clean:
	rm -rf $(BUILD) $(SAN_BUILD) out
