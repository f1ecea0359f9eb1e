# Two commands do all the set-up on a fresh machine:
#   make demo   builds the embedded default (the paper's cube -> sphere-like surface) and reports on it
#   make test   runs the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test,bench,cad,batch,docs]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/g1patch demo --out out

test: $(STAMP)
	$(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_evaluate.py
	$(BIN)/python benchmarks/bench_build.py
	$(BIN)/python benchmarks/bench_split4.py
	$(BIN)/python benchmarks/bench_shape.py
	$(BIN)/python benchmarks/bench_limit.py
	$(BIN)/python benchmarks/bench_interpolants.py
	$(BIN)/python benchmarks/bench_check.py
	$(BIN)/python benchmarks/bench_readers.py
	$(BIN)/python benchmarks/bench_files.py
	$(BIN)/python benchmarks/bench_cad.py
	$(BIN)/python benchmarks/bench_polygon.py
	$(BIN)/python benchmarks/bench_scaling.py

clean:
	rm -rf $(VENV) out
