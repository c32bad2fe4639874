# make demo: the main job on the embedded default (SQLite); make test: the test suite. Both set up .venv themselves.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
DEMO_DIR ?= demo-out

.PHONY: venv test demo bench clean

venv: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -e '.[dev,cluster,viewer]'
	touch $(STAMP)

test: venv
	$(PY) -m pytest

demo: venv
	mkdir -p $(DEMO_DIR)
	$(VENV)/bin/vinadv maps generate --n 1000 --size 28 --seed 0 --out $(DEMO_DIR)/maps.npz
	$(VENV)/bin/vinadv maps show $(DEMO_DIR)/maps.npz --index 0 --all-starts --out $(DEMO_DIR)/map0.png

bench: venv
	$(PY) benchmarks/grid.py

clean:
	rm -rf $(VENV) $(DEMO_DIR) .pytest_cache .hypothesis
