# The two commands of the quick start, and a few more for developers.
#   make run    build, then run fremend in the foreground with its embedded defaults: gRPC on
#               127.0.0.1:50051, data in ./fremen-data (gitignored); Ctrl-C stops it cleanly.
#               Settings: make run ARGS="--listen 127.0.0.1:6000 --log-level debug"
#   make test   install what is missing, build, run every test
#   make demo-eval  the offline accuracy evaluation of the model on generated data
BUILD ?= build
JOBS ?= $(shell nproc)

ARGS ?=

.PHONY: all deps configure build run demo-eval test bench asan tsan sanitize-ci asan-ci tsan-ci fuzz fuzz-smoke \
        thread-safety clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release >/dev/null

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

run: build
	@$(BUILD)/bin/fremend $(ARGS)

demo-eval: build
	@bash scripts/run-demo-eval.sh $(BUILD)/bin

# Every test, then how many each suite ran (tests/test_suites.py; the suites ctest must hold are
# listed in tests/expected_suites.txt and checked by the test meta.suites_registered).
test: build
	@cd $(BUILD) && status=0; ctest --output-on-failure -j$(JOBS) --output-junit ctest-junit.xml || status=$$?; \
	  /usr/bin/python3 $(CURDIR)/tests/test_suites.py summary ctest-junit.xml $(CURDIR)/tests/expected_suites.txt; \
	  exit $$status

bench: build
	@$(BUILD)/bin/fremen_model_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

# Sanitizer builds in their own trees.
asan: deps
	@cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFREMEN_SANITIZE=address >/dev/null
	@cmake --build build-asan -j$(JOBS) && cd build-asan && ctest --output-on-failure -j$(JOBS)

tsan: deps
	@cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFREMEN_SANITIZE=thread >/dev/null
	@cmake --build build-tsan -j$(JOBS) && cd build-tsan && ctest --output-on-failure -j$(JOBS)

# CI's sanitizer step: only the storage and server unit suites, each under ASan+UBSan and under
# TSan (a whole build of everything per sanitizer would not fit CI's time).
SANITIZE_TESTS ?= fremen_storage_test fremen_server_test

sanitize-ci: asan-ci tsan-ci

asan-ci: deps
	@bash scripts/sanitize-ci.sh address build-asan $(JOBS) $(SANITIZE_TESTS)

tsan-ci: deps
	@bash scripts/sanitize-ci.sh thread build-tsan $(JOBS) $(SANITIZE_TESTS)

# clang's thread-safety analysis (ABSL_GUARDED_BY and friends) over the storage, server and client
# libraries, in build-tsa/: any locking annotation violated fails the build.
thread-safety: deps
	@bash scripts/install-deps.sh clang
	@bash scripts/thread-safety-check.sh build-tsa $(JOBS)

# libFuzzer targets (fuzz/README.md), built with clang in build-fuzz/; each runs FUZZ_SECONDS.
FUZZ_SECONDS ?= 60

fuzz:
	@bash scripts/install-deps.sh fuzz
	@bash fuzz/run.sh build-fuzz $(FUZZ_SECONDS) $(JOBS)

fuzz-smoke:
	@bash scripts/install-deps.sh fuzz
	@bash fuzz/run.sh build-fuzz 10 $(JOBS)

clean:
	@rm -rf $(BUILD) build-asan build-tsan build-fuzz build-tsa
