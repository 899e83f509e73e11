# Radiosity Baker — developer entry points. `make demo` and `make test` set up
# .venv (idempotent: reinstalls only when requirements.txt changes) first.
PYTHON_BOOTSTRAP ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.requirements-installed
OUT ?= out

.PHONY: setup check-system demo test bench bench-quick extension clean

setup: check-system $(STAMP)

check-system:
	@$(PYTHON_BOOTSTRAP) -c "import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)" || \
	  { echo "error: Python 3.11 is needed (bpy 5.0.1 supports only 3.11); install python3.11 or set PYTHON_BOOTSTRAP"; exit 1; }
	@$(PYTHON_BOOTSTRAP) -c "import ctypes.util as u, sys; sys.exit(0 if u.find_library('EGL') and u.find_library('GL') else 1)" || \
	  { echo "error: OpenGL/EGL libraries missing; install them: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri"; exit 1; }

$(STAMP): requirements.txt
	$(PYTHON_BOOTSTRAP) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	touch $@

demo: setup
	$(PY) -m radiosity_addon solve cornell-box --method hemicube --subdiv 6 \
	  --output $(OUT)/cornell-box.npz --report $(OUT)/cornell-box-report.json

test: setup
	$(PY) -m pytest

# accuracy vs time against Cycles and exact answers, and the dissertation's Table 5.1
# (the Cycles reference is cached in $(OUT)/bench*/cache, so reruns are cheap)
bench: setup
	$(PY) -m radiosity_addon bench --output-dir $(OUT)/bench

bench-quick: setup
	$(PY) -m radiosity_addon bench --quick --output-dir $(OUT)/bench-quick

clean:
	rm -rf $(OUT) dist build .pytest_cache
