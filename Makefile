# Two commands set everything up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev,sim,plots,interop,campaigns]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/auv validate missions/field_survey.yaml
	$(BIN)/auv simulate missions/field_survey.yaml --out runs/demo

test: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -n auto --dist worksteal --durations=20

lint: $(STAMP)
	$(BIN)/ruff check mission planners perception_plugins tests
	$(BIN)/mypy

clean:
	rm -rf $(VENV) runs .pytest_cache .mypy_cache .ruff_cache
