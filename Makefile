# make demo: the main job on the embedded default (SQLite); make test: the test suite; make docs: the documentation
# site (site/index.html). Each sets up .venv itself; constraints.txt pins the exact builds (pyproject.toml: ranges).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
DEMO_DIR ?= demo-out
DEMO_FLAGS ?=
# pytest's worker processes (pytest-xdist): 2 by default, measured faster on the 2-core machine (docs/development.md);
# TEST_WORKERS= (empty) runs one process
TEST_WORKERS ?= 2
WORKERS_FLAG := $(if $(TEST_WORKERS),-n $(TEST_WORKERS))

.PHONY: venv browser test test-fast demo docs perf clean

venv: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -c constraints.txt -e '.[dev,cluster,viewer,docs]'
	touch $(STAMP)

# headless Chromium for the viewer's browser test (tests/viewer/test_browser.py); quick when already installed
browser:
	@command -v chromium >/dev/null 2>&1 || (apt-get update -qq && apt-get install -y -qq chromium) \
		|| echo "warning: could not install chromium; the browser test will be skipped (it fails when CI=true)"

test: venv browser
	$(PY) -m pytest $(WORKERS_FLAG)

# the quick part of the suite while working (under a minute): everything not marked slow
test-fast: venv
	$(PY) -m pytest $(WORKERS_FLAG) -m "not slow"

# the whole paper: run, classifier comparison (quick profile; DEMO_FLAGS=--no-evaluate skips it), report; about
# 2 minutes on the 2-core machine from a fresh clone (1 min 51 s measured: the .venv, compiling the Numba kernels, the
# job and the report), plus the packages' download on a machine whose pip cache is empty
demo: venv
	@echo "make demo: the main job on 5,000 maps, the classifier comparison and the report: about 2 minutes on 2 cores"
	mkdir -p $(DEMO_DIR)
	rm -f $(DEMO_DIR)/vinadv.db
	$(VENV)/bin/vinadv run --n 5000 --size 28 --attack near-path --seed 0 --db $(DEMO_DIR)/vinadv.db --name demo --report $(DEMO_DIR)/report $(DEMO_FLAGS)
	@echo "open $(DEMO_DIR)/report/index.html; look at the pairs with: $(VENV)/bin/vinadv serve --db $(DEMO_DIR)/vinadv.db"

# the documentation site into site/ (mkdocs.yml); --strict: a broken link or docstring reference fails the build
docs: venv
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet

# the main speed measurements (perf/: ratios measured side by side in one run)
perf: venv
	for b in grid planning attacks classify store; do $(PY) perf/$$b.py || exit 1; done

clean:
	rm -rf $(VENV) $(DEMO_DIR) site .pytest_cache .hypothesis
