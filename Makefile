# Two entry points: `make demo` (install + run the main job) and `make test` (install + run the tests).
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
STORE ?= artifacts/demo
# Reconstruction iterations per sequence for `make demo` (empty: the ReconstructionConfig default, 900;
# about 10 minutes for the two demo sequences on 2 cores). `make demo ITERATIONS=200` is a quick look.
ITERATIONS ?=
# Scenarios the mining loop accepts per demo sequence (rule-based client; 0: no mining).
MINE ?= 2
# torch is pinned to 2.13.0. PyPI's Linux wheel of it bundles CUDA (several GB); on a machine without a GPU
# pass PyTorch's CPU wheel index to get the CPU build: make test TORCH_INDEX=https://download.pytorch.org/whl/cpu
TORCH_INDEX ?=
export PREFECT_SERVER_ANALYTICS_ENABLED := false
export RAY_AUTH_MODE := disabled

.PHONY: install demo test lint browser bench clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet $(if $(TORCH_INDEX),--extra-index-url $(TORCH_INDEX)) -e '.[dev,rerun]'
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/simsplat run --store $(STORE) --sequences 2 --mine $(MINE) $(if $(ITERATIONS),--iterations $(ITERATIONS)) $(if $(filter-out 0,$(MINE)),--export $(STORE)/datasets)
	$(VENV)/bin/simsplat assets build --store $(STORE)
	$(VENV)/bin/simsplat inspect $(STORE)/logs/synth-000000 --sheet $(STORE)/contact_sheet.png --frame 20
	$(VENV)/bin/simsplat render --store $(STORE) --seq synth-000000 --frame 20 --out $(STORE)/render_frame20.png
	$(VENV)/bin/simsplat render --store $(STORE) --seq synth-000000 --frame 20 --shift-left 1 \
		--out $(STORE)/novel_view_frame20_left1m.png
	$(VENV)/bin/simsplat query --store $(STORE) --seq synth-000000 "the red car turning right" \
		--out $(STORE)/query_red_car_turning_right.png
	$(VENV)/bin/simsplat search --store $(STORE) "a pedestrian crossing in front of us while a car turns"
	$(VENV)/bin/simsplat edit --store $(STORE) --seq synth-000000 \
		"remove the white van and make the red car stop before the crosswalk"
	$(VENV)/bin/simsplat edit --store $(STORE) --seq synth-000000 "add a yellow taxi in our lane 15 m ahead"

test: $(STAMP) lint browser
	$(VENV)/bin/simsplat deploy check
	$(VENV)/bin/pytest -q --durations=25

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

# The dashboard's browser tests drive Debian's chromium through playwright (its own browser download is not
# reachable); as root (CI) it is installed when missing, otherwise the browser tests say how and skip.
browser:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	else echo "no chromium: the dashboard's browser tests will skip (sudo apt-get install chromium)"; fi

bench: $(STAMP)
	$(PY) bench/bench_world.py

clean:
	rm -rf artifacts .pytest_cache
