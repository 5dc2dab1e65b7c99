# Two commands: `make demo` and `make test`. Both install missing Debian packages first.
# Also: `make install PREFIX=/opt/cairn` (default /usr/local) and `make package` (a .deb in
# $(BUILD_DIR); docs/use_from_cpp.md).
BUILD_DIR ?= build
PREFIX ?= /usr/local
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
DATA_ROOT ?= $(abspath ../shared/data)
export CAIRN_DATA_ROOT ?= $(DATA_ROOT)

.PHONY: all deps configure build test demo clean fuzz install package

all: build

deps:
	@./scripts/install_deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) > $(BUILD_DIR).configure.log 2>&1 \
	  || (cat $(BUILD_DIR).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --timeout 600

install: build
	@cmake --install $(BUILD_DIR) --prefix $(PREFIX)

# cpack -G DEB (cmake/CairnPackaging.cmake): $(BUILD_DIR)/cairn_<version>_<arch>.deb.
package: build
	@cd $(BUILD_DIR) && cpack -G DEB
	@ls -1 $(BUILD_DIR)/cairn_*.deb

demo: build
	@./scripts/demo.sh $(BUILD_DIR)/src/cairn/cli/cairn

# libFuzzer targets with clang (not part of `make test`; the corpora run in `make test`).
fuzz: deps
	@cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCAIRN_BUILD_FUZZERS=ON \
	  -DCAIRN_BUILD_TESTS=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
	@cmake --build build-fuzz -j $(JOBS) --target fuzz_graph fuzz_trajectory fuzz_carmen fuzz_bal fuzz_point_cloud fuzz_image_sequence \
	  fuzz_calibration fuzz_landmarks fuzz_saved_map fuzz_ros1_bag fuzz_mcap fuzz_rosbag2_sqlite fuzz_cdr fuzz_gnss_csv fuzz_imu fuzz_transform fuzz_map3d
	@echo "run e.g.: build-fuzz/fuzz/fuzz_graph -max_total_time=300 fuzz/corpus/graph"

clean:
	rm -rf $(BUILD_DIR) build-fuzz $(BUILD_DIR).configure.log
