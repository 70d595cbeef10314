# Every target sets up what it needs from nothing: a .venv made with the system python3,
# packages from PyPI. `make demo` and `make test` are the two commands of the README.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: demo test bench docs lint format clean

$(STAMP): pyproject.toml
	@# Offscreen rendering of the twin needs EGL (Debian: libegl1, libgl1-mesa-dri).
	@ldconfig -p | grep -q libEGL.so.1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null \
		&& apt-get update -qq && apt-get install -y -qq libegl1 libgl1-mesa-dri; } \
		|| echo "note: no EGL library: pictures of the arm will be skipped"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/leadthrough demo

test: $(STAMP)
	@# one worker per core (pytest-xdist): 3.5–6 min on 2 cores, 8.5 min on one
	$(BIN)/python -m pytest -q -n auto

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_dynamics.py
	$(BIN)/python benchmarks/bench_twin.py
	$(BIN)/python benchmarks/bench_observer.py
	$(BIN)/python benchmarks/bench_step.py
	$(BIN)/python benchmarks/effort_limits.py
	$(BIN)/python benchmarks/effort_plants.py
	$(BIN)/python benchmarks/guiding_quality.py
	$(BIN)/python benchmarks/guiding_quality.py --seeds 5-8
	$(BIN)/python benchmarks/guiding_quality.py --seeds 9-12 --plants position_amplitude=0.25 friction_scale=0.7,1.3
	$(BIN)/python benchmarks/guiding_quality.py --identified
	$(BIN)/python benchmarks/guiding_quality.py --dt 0.008
	$(BIN)/python benchmarks/guiding_quality.py --cases contact
	$(BIN)/python benchmarks/margin_tradeoff.py --out build/margin_runs
	$(BIN)/python benchmarks/replay_quality.py
	$(BIN)/python benchmarks/replay_quality.py --dt 0.008
	$(BIN)/python benchmarks/calibration_accuracy.py
	$(BIN)/python benchmarks/calibration_drift.py
	$(BIN)/python benchmarks/hand_impedance.py
	$(BIN)/python benchmarks/real_identification.py
	$(BIN)/python benchmarks/payload_twin.py
	$(BIN)/python benchmarks/real_observer.py

# Every figure, table and number the README shows, from seeded runs (a few minutes).
docs: $(STAMP)
	MUJOCO_GL=$${MUJOCO_GL:-egl} $(BIN)/python -m leadthrough.experiments.docs

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

format: $(STAMP)
	$(BIN)/ruff format .
	$(BIN)/ruff check --fix .

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache .ruff_cache
