# Two commands do all the set-up on a fresh machine:
#   make demo   -- reproduce the paper's Section 5 study (figures in out/)
#   make test   -- run the test suite (unit tests, doctests, notebooks, docs)
#                  on the machine's cores
#   make docs   -- build the documentation site into docs/_build/html
#   make docs-check -- build it and look at it in headless Chromium
#                  (screenshots in docs/_build/screenshots; needs chromium:
#                  sudo apt-get install -y chromium)
#   make bench  -- run every benchmark script
#   make clean-cache -- remove numba's compiled cache: numba re-compiles a
#                  function when its own file changes, not when a function
#                  it calls in another file does, so run this after editing
#                  a compiled function (e.g. backlash_step)
#   make clean  -- the same, and remove .venv, out/ and the built docs
# Both create the virtual environment .venv and install sandwichctl into it
# the first time.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench docs docs-check clean clean-cache

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/python -m sandwichctl demo --out out

# pytest-xdist runs the test files on every core (at most four), each file's
# tests in one worker so that its module fixtures are built once
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4 --dist loadfile

# The notebooks are executed at build time through jupyter-cache, which
# re-runs a notebook only when its code changes; the cache is cleared so
# that the pages show what the current package computes.
docs: $(STAMP)
	rm -rf docs/_build/.jupyter_cache
	env -u MPLBACKEND $(BIN)/python -m sphinx -W -n -b html docs docs/_build/html

docs-check: $(STAMP)
	$(BIN)/python docs/_tools/check.py

bench: $(STAMP)
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean-cache:
	find sandwichctl -name '*.nbi' -delete -o -name '*.nbc' -delete

clean: clean-cache
	rm -rf $(VENV) out docs/_build
