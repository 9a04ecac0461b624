# `make demo`: set up .venv and reproduce the paper (carnot paper).
# `make test`: set up .venv and run ruff, mypy (beside the tests) and the whole test suite.
# `make bench`: every benchmark of benchmarks/ (a quarter of an hour or more).
# `make docs`: the documentation site into docs/_build/html (warnings are errors; offline).
# `make browser`: Debian's chromium (for the browser test of carnot explore), if missing.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean docs browser

$(STAMP): pyproject.toml requirements.lock
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --no-compile -r requirements.lock
	@# (the bytecode on every core: pip compiles it on one, 15 of its 57 s here; not the
	@# packages' own tests, which nothing here imports: a third of SymPy's and SciPy's code)
	$(BIN)/python -c "import compileall, re, sys; compileall.compile_dir(sys.argv[1], quiet=2, workers=0, rx=re.compile(r'/tests/'))" $(VENV)/lib
	$(BIN)/python -m pip install -q --no-deps -e .
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/carnot paper

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples docs
	$(BIN)/mypy src/carnot

# (one BLAS thread per worker: the 2 workers hold the 2 cores; a worker's multithreaded BLAS
# competing with the other's made a 216 x 216 solve 25x slower under load. tests/conftest.py's
# scheduler puts the tests of each heavy Numba kernel on one worker, so that each kernel
# compiles once, and the run ends with the compiles it paid. CARNOT_MYPY=1: conftest.py runs
# mypy beside the tests, its output in the summary and its failure the run's: alone, before
# them, it held one core for half a minute on a clean clone while the other idled)
test: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples docs
	OPENBLAS_NUM_THREADS=1 CARNOT_MYPY=1 $(BIN)/python -m pytest -n 2 --durations=15

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_single_impact.py
	$(BIN)/python benchmarks/bench_symbolic.py
	$(BIN)/python benchmarks/bench_friction.py
	$(BIN)/python benchmarks/bench_batch.py
	$(BIN)/python benchmarks/bench_batch_coulomb.py
	$(BIN)/python benchmarks/bench_sweep.py
	$(BIN)/python benchmarks/bench_systems.py
	$(BIN)/python benchmarks/bench_several.py
	$(BIN)/python benchmarks/bench_several_groups.py
	$(BIN)/python benchmarks/bench_multiple.py
	$(BIN)/python benchmarks/bench_dispersion.py
	$(BIN)/python benchmarks/bench_batch_multi.py
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_audit.py
	$(BIN)/python benchmarks/bench_startup.py

docs: $(STAMP)
	$(BIN)/sphinx-build -b html -W --keep-going -q docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

# apt needs root: run as root (CI is), or with SUDO=sudo.
SUDO ?=
browser:
	@if [ -x /usr/bin/chromium ]; then echo "chromium: $$(/usr/bin/chromium --version 2>/dev/null)"; \
	else $(SUDO) apt-get update -q && \
	DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q chromium chromium-driver; fi

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache .mypy_cache .ruff_cache .hypothesis
	rm -rf docs/_build docs/generated docs/auto_examples
