# tessera — the README's two commands, set-up included.
#   make run    install what is missing, build, serve with the built-in Cornell box queued
#   make test   install what is missing, build, run the whole suite through ctest
# Also: make build, make deps, make test-asan, make test-tsan, make fuzz, make bench (+ bench-deps),
#       make bench-compare, make image (+ image-deps), make mutants (the mutation campaign,
#       tests/mutation/README.md), make clean.

BUILD      ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_ARGS ?=

# Debian packages the build and tests need (docs/design.md §3).
DEB_PACKAGES := cmake make gcc pkg-config libembree-dev libopenexr-dev libpng-dev libcjson-dev nettle-dev \
                libmicrohttpd-dev libarchive-dev libcmocka-dev libcurl4-openssl-dev \
                clang libclang-rt-14-dev wrk curl
# (clang + libclang-rt: the libFuzzer harnesses, whose smoke runs are part of `make test`;
#  wrk + curl: the load test bench/load, whose light version is part of `make test`.)
# Optional: installed when possible; without them the tests that need them say so and skip.
#  chromium: the browser tests of the web UI, tests/browser.
OPTIONAL_PACKAGES := chromium
# Benchmark-only (installed by `make bench`, never by `make test`): Blender for the Cycles
# comparison (bench/cycles), bc for the timing arithmetic of the bench scripts, valgrind for
# the instruction counts of bench_effects, gnuplot-nox for the accuracy plots.
BENCH_PACKAGES := blender bc valgrind gnuplot-nox
# Container image only (installed by `make image` and the container test, never by `make deps`):
# podman with runc builds and runs the image of docker/Dockerfile; catatonit is the pause
# process of the pods `podman kube play` runs; debootstrap makes the local Debian base images
# where no registry is reachable (docker/README.md).
IMAGE_PACKAGES := podman runc catatonit debootstrap

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: all run test build deps test-asan test-tsan fuzz fuzz-build bench bench-compare bench-deps image image-deps mutants clean

all: build

# $(call install_missing,TARGET,PACKAGES): apt-get installs those of PACKAGES not installed.
define install_missing
	@missing=""; \
	for p in $(2); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "$(1): installing from Debian:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing >/dev/null && \
	  echo "$(1): done"; \
	fi
endef

# node and npm build the web UI (web/, Vite) and run its browser tests: Debian's nodejs and
# npm, installed when either command is missing (a node from elsewhere that brings its own
# npm, as NodeSource's does, is used as it is: its package conflicts with Debian's npm).
WEB_PACKAGES := nodejs npm

deps:
	$(call install_missing,deps,$(DEB_PACKAGES))
	@if ! command -v node >/dev/null || ! command -v npm >/dev/null; then \
	  echo "deps: installing from Debian: $(WEB_PACKAGES) (the web UI's build)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $(WEB_PACKAGES) >/dev/null && \
	  echo "deps: done"; \
	fi
	@for p in $(OPTIONAL_PACKAGES); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' && continue; \
	  echo "deps: installing optional $$p"; \
	  { $(SUDO) apt-get update -qq && \
	    DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$p >/dev/null; } || \
	    echo "deps: could not install $$p; the tests that need it will report SKIPPED"; \
	done

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# The main job: `tessera serve` on $(BIND):$(PORT) at once, with the built-in Cornell box
# queued as its first job; the server prints the URL to watch it and where its image will
# be (Ctrl-C stops it). `tessera render -o cornell.exr` renders it to a file instead.
BIND ?= 127.0.0.1
PORT ?= 8080
run: build
	@echo "run: serving; open http://$(BIND):$(PORT)/ in a browser (Ctrl-C to stop)"
	$(BUILD)/tessera serve --bind $(BIND) --port $(PORT) --queue-builtin

# TEST_ENV: environment (and wrapper) for the ctest run; the sanitizer targets set it.
TEST_ENV ?=
test: build
	$(TEST_ENV) ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

# Sanitizer runs stop at the first report (halt_on_error), with a leak check under ASan.
# TSan's runtime (GCC 12) cannot map its shadow memory when the kernel randomises mmap
# with more than 28 bits (vm.mmap_rnd_bits = 32 on recent kernels), so the run goes under
# `setarch -R` (no ASLR) wherever the container allows that personality.
ASAN_ENV  = ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:abort_on_error=0:strict_string_checks=1 \
            UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
TSAN_ENV  = TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$(CURDIR)/tests/tsan.supp \
            $(shell setarch $$(uname -m) -R true 2>/dev/null && echo setarch $$(uname -m) -R)

test-asan:
	$(MAKE) test BUILD=build-asan BUILD_TYPE=RelWithDebInfo CMAKE_ARGS=-DTS_SANITIZE=address TEST_ENV="env $(ASAN_ENV)"

test-tsan:
	$(MAKE) test BUILD=build-tsan BUILD_TYPE=RelWithDebInfo CMAKE_ARGS=-DTS_SANITIZE=thread TEST_ENV="env $(TSAN_ENV)"

# Fuzzing (tests/fuzz/README.md): harnesses built by clang with libFuzzer, ASan and UBSan in
# their own folder; `make fuzz` runs each for FUZZ_SECONDS, keeping what it finds in
# $(FUZZ_BUILD)/fuzz-corpus. `make test` runs each for a few seconds (ctest fuzz_*).
FUZZ_BUILD   ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZERS      ?= scene obj ply bsdf exr json http sse pbrt teximage

$(FUZZ_BUILD)/CMakeCache.txt: | deps
	CC=clang cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTS_FUZZ=ON -DTS_WERROR=OFF

fuzz-build: deps $(FUZZ_BUILD)/CMakeCache.txt
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_all

fuzz: fuzz-build
	tests/fuzz/run.sh --keep $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZERS)

bench-deps:
	$(call install_missing,bench-deps,$(BENCH_PACKAGES))

bench: build bench-deps
	@if [ -x bench/run ]; then bench/run $(BUILD); else echo "bench: no benchmarks yet"; fi

# The container image (docker/README.md): docker/build-image.sh builds docker/Dockerfile with
# podman (or docker where that is what a user has), making the Debian base images first
# (debootstrap) when they are missing and no registry answers, and prints the image's size.
IMAGE ?= tessera:latest
# (CONTAINER_ENGINE=docker: of these, only debootstrap.)
image-deps:
	$(call install_missing,image-deps,$(if $(filter docker,$(CONTAINER_ENGINE)),debootstrap,$(IMAGE_PACKAGES)))

image: image-deps
	docker/build-image.sh $(IMAGE)

# The speed targets in one table (bench/compare.sh): render ÷ Embree rays/s per scene, 2 threads
# ÷ 1 thread, and tessera ÷ Cycles at equal RMSE where Blender is installed.
bench-compare: build
	bench/compare.sh $(BUILD)

# The mutation campaign (tests/mutation/README.md): each mutant of tests/mutation/mutants.txt
# applied to a scratch copy of the tree, rebuilt, and the renderer-level tests run against
# it; prints which test killed it and the kill rate. By hand only, never part of `make test`.
# MUTANTS_ARGS passes options, e.g. MUTANTS_ARGS="--only M19 --keep".
MUTANTS_ARGS ?=
mutants: deps
	tests/mutation/run $(MUTANTS_ARGS)

clean:
	rm -rf build build-asan build-tsan build-fuzz cornell.exr cornell.png
