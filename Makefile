# Two commands do all the set-up on a fresh machine:
#   make demo   -- reproduce the paper's Section 5 study (figures in out/)
#   make test   -- run the test suite (unit tests, doctests, notebooks, docs)
#   make docs   -- build the documentation site into docs/_build/html
#   make bench  -- run every benchmark script
# Both create the virtual environment .venv and install sandwichctl into it
# the first time.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/python -m sandwichctl demo --out out

test: $(STAMP)
	$(BIN)/python -m pytest -q

docs: $(STAMP)
	$(BIN)/python -m sphinx -W -b html docs docs/_build/html

bench: $(STAMP)
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) out
