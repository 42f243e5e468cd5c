# handdb: `make demo` builds the demo database, `make test` runs the whole suite.
# Both create the virtual environments they need on a fresh machine.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
INSTALLED := $(VENV)/.installed
# Blender (bpy 4.5) pins numpy 1.26 while handdb needs numpy 2: it gets its own venv,
# used only by the test that imports exported USD files into Blender.
BLENDER_VENV := .venv-blender
BLENDER_INSTALLED := $(BLENDER_VENV)/.installed
PYTEST_WORKERS ?= 2

.PHONY: install demo test test-fast bench lint clean

$(INSTALLED): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --editable '.[test]'
	touch $@

$(BLENDER_INSTALLED):
	$(PYTHON) -m venv $(BLENDER_VENV)
	$(BLENDER_VENV)/bin/pip install --quiet 'bpy>=4.5,<4.6'
	touch $@

install: $(INSTALLED)

demo: $(INSTALLED)
	$(BIN)/handdb demo

test: $(INSTALLED) $(BLENDER_INSTALLED)
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadfile -q

test-fast: $(INSTALLED)
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadfile -q -m "not slow"

bench: $(INSTALLED)
	$(BIN)/python benchmarks/run.py

lint: $(INSTALLED)
	$(BIN)/ruff check handdb flows tests benchmarks notebooks
	$(BIN)/mypy handdb flows

clean:
	rm -rf data .prefect .pytest_cache benchmarks/out
