# Every target that runs code first makes sure the environment exists, so a
# fresh machine needs nothing but `make demo` or `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
BENCH_STAMP := $(VENV)/.bench-installed
# open3d needs libusb and libgomp at import time; MuJoCo's headless renderer
# needs EGL (GPU-less Mesa) with OSMesa as the fallback.
SYSTEM_LIBS := libusb-1.0-0 libgomp1 libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri libosmesa6

.PHONY: setup system-libs test docs demo bench lint clean

setup: $(STAMP)

system-libs:
	@missing=""; for p in $(SYSTEM_LIBS); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing system libraries:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO="sudo"; \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing; \
	fi

$(STAMP): pyproject.toml setup.py | system-libs
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e ".[dev]"
	touch $(STAMP)

# The documentation site first (cheap, and a broken link or docstring fails it), then the tests, on
# TEST_WORKERS processes (pytest-xdist); each test module runs whole in one of them, so its fixtures are
# built once. Two workers take the suite from 19 to 10.5 minutes on a 2-core machine.
TEST_WORKERS ?= 2
test: setup docs
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadscope

# mkdocs.yml; the benchmark tables come from benchmarks/results/*.json (docs/hooks/results.py). Writes site/.
# NO_MKDOCS_2_WARNING silences mkdocs-material's banner about MkDocs 2, which is no warning about this site.
docs: setup
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

demo: setup
	$(BIN)/python -m psorr.demo
	$(BIN)/psorr-sim run tasks/demo.yaml --episodes 2 --seed 0 --occluder on --record out/demo

# The benchmarks compare with peers in one run: the bench extra brings OpenCV's PPF.
$(BENCH_STAMP): pyproject.toml setup.py | $(STAMP)
	$(BIN)/pip install -q -e ".[bench]"
	touch $(BENCH_STAMP)

bench: setup $(BENCH_STAMP)
	$(BIN)/python benchmarks/decompose.py
	$(BIN)/python benchmarks/segment_osd.py
	$(BIN)/python benchmarks/kernels.py
	$(BIN)/python benchmarks/osd_false_positives.py
	$(BIN)/python benchmarks/table1.py
	$(BIN)/python benchmarks/verify_compiled.py
	$(BIN)/python benchmarks/peers.py
	$(BIN)/python benchmarks/psg.py
	$(BIN)/python benchmarks/generalization.py
	$(BIN)/python benchmarks/library_size.py
	$(BIN)/python benchmarks/sensors.py
	$(BIN)/python benchmarks/density.py
	$(BIN)/python benchmarks/grasp_tolerance.py
	$(BIN)/python benchmarks/episodes.py

lint: setup
	$(BIN)/ruff check psorr sim tests benchmarks

clean:
	rm -rf $(VENV) build *.egg-info
