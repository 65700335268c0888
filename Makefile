# tetherlab: every target builds its own virtual environment from pinned versions.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: venv test test-all verify bench clean

venv: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -c constraints.txt -e '.[dev,oracle]'
	touch $(STAMP)

# Fast checks (CI): everything not marked slow or oracle.
test: $(STAMP)
	$(PY) -m pytest -q -m "not slow and not oracle" -p no:cacheprovider

# Every check, slow ones included.
test-all: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider

# Reproduce every report into reports/; exits non-zero when a gate fails.  The sections run on
# 2 worker processes (the machine and CI have 2 cores; VERIFY_JOBS=1 runs them one after the
# other in one process); the report is the same either way.
VERIFY_JOBS ?= 2
verify: $(STAMP)
	$(PY) -m tetherlab.verify --out reports --jobs $(VERIFY_JOBS)
	$(PY) -m pytest -q -p no:cacheprovider tests/test_report.py   # the page in a headless browser (skipped without Chromium)

# Speed and memory targets: prints a table (never asserted in tests).
bench: $(STAMP)
	$(PY) -m tetherlab.bench

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info
