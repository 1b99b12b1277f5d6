# The README's two commands: `make demo` (the main job on the default scene) and `make test`.
# Both start from a fresh Debian 12 machine: missing packages are installed with apt-get.

BUILD_DIR  ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc)
OUT_DIR    ?= out
SHARCBAKE  := $(BUILD_DIR)/bin/sharcbake

# Debian packages the build, the demo and the tests need.
DEB_PACKAGES := build-essential cmake pkg-config python3 \
    libembree-dev libtbb-dev libopenvdb-dev libopenexr-dev libglm-dev libcli11-dev \
    libtinygltf-dev libdraco-dev libmeshoptimizer-dev libwebp-dev nlohmann-json3-dev libstb-dev libboost-iostreams-dev libgtest-dev libbenchmark-dev \
    libopenvdb-tools python3-openvdb python3-jsonschema clang libclang-rt-14-dev gnuplot-nox parallel blender gltfpack

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: all deps configure build demo test clean

all: build

# Installs only what is missing, so a second run costs nothing and needs no network.
deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	    echo "Installing Debian packages:$$missing"; \
	    $(SUDO) apt-get update -q && \
	    DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q --no-install-recommends $$missing; \
	else echo "All Debian packages present."; fi

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

demo: build
	@mkdir -p $(OUT_DIR)
	$(SHARCBAKE) render scenes/cornell_box/cornell_box.gltf -o $(OUT_DIR)/cornell_box_reference.exr \
	    --resolution 160x160 --spp 1024
	$(SHARCBAKE) bake scenes/cornell_box/cornell_box.gltf -o $(OUT_DIR)/cornell_box.sharc \
	    --stats-json $(OUT_DIR)/cornell_box_bake.json \
	    --report $(OUT_DIR)/report --reference $(OUT_DIR)/cornell_box_reference.exr
	$(SHARCBAKE) render scenes/cornell_box/cornell_box.gltf -o $(OUT_DIR)/cornell_box_cached.exr \
	    --resolution 160x160 --spp 64 --cache $(OUT_DIR)/cornell_box.sharc
	$(SHARCBAKE) render scenes/cornell_box/cornell_box.gltf -o $(OUT_DIR)/cornell_box_cache_view.exr \
	    --resolution 160x160 --spp 4 --cache $(OUT_DIR)/cornell_box.sharc --debug-view cache -q
	$(SHARCBAKE) compare $(OUT_DIR)/cornell_box_cached.exr $(OUT_DIR)/cornell_box_reference.exr
	@echo "Demo outputs are in $(OUT_DIR)/: cornell_box.sharc (the baked cache), cornell_box_bake.json"
	@echo "(bake statistics), cornell_box_cached.exr/.png (paths ending on the cache),"
	@echo "cornell_box_cache_view.exr/.png (the cache seen from the camera) and"
	@echo "cornell_box_reference.exr/.png (plain path tracing, 1024 spp; the error above is against it)."
	@echo "Error against run time: $(OUT_DIR)/report/convergence.png, first panel the cache against its"
	@echo "probe reference, falling to its bias floor (tables: convergence.csv,"
	@echo "plain_path_tracing.csv, convergence.json; docs/error_report.md explains them)."

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD_DIR) $(OUT_DIR)
