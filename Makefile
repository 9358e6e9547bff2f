PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test docs lint bench clean clean-cache

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[all,dev,docs]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/psm-grasp demo --out out

test: $(STAMP)
	$(BIN)/ruff check envs optim cli tests scripts
	$(BIN)/python -m pytest -q
	$(BIN)/mkdocs build --strict

# the documentation site (mkdocs.yml): a strict build, then served at http://127.0.0.1:8000
docs: $(STAMP)
	$(BIN)/mkdocs build --strict
	$(BIN)/mkdocs serve

lint: $(STAMP)
	$(BIN)/ruff check envs optim cli tests scripts

bench: $(STAMP)
	$(BIN)/python scripts/bench_solver.py
	$(BIN)/python scripts/bench_env.py

# the kernels are cached per version of the source (envs/_kernel_cache.py), so an edit needs no
# clearing; this frees the disk (and clears numba's per-file caches of older checkouts)
clean-cache:
	find envs -name '*.nbi' -delete -o -name '*.nbc' -delete
	rm -rf envs/__pycache__/numba-*

clean: clean-cache
	rm -rf $(VENV) out .pytest_cache site
