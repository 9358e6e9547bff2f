PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[all,dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/psm-grasp demo --out out

test: $(STAMP)
	$(BIN)/ruff check envs optim tests scripts
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check envs optim tests scripts

bench: $(STAMP)
	$(BIN)/python scripts/bench_solver.py
	$(BIN)/python scripts/bench_env.py

clean:
	rm -rf $(VENV) out .pytest_cache
