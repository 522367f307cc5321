# gpo: `make test` checks everything, `make demo` runs the main job into out/, `make lab` opens the notebooks.
# `make book` builds the executed notebooks, without running them, into a static HTML site: out/book/index.html.
# Each creates .venv from environment.txt first when it is missing or environment.txt has changed.

PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.environment.stamp

.PHONY: test demo lab book env clean

env: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	rm -rf $(VENV)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -r environment.txt
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m gpo recording sample short1 short2 short3 long1 long2 long3 \
		downward-wood downward-raised downward-industrial
	$(BIN)/python -m gpo table4
	$(BIN)/python -m pytest -p no:cacheprovider

demo: $(STAMP)
	$(BIN)/python -m gpo demo --out out

lab: $(STAMP)
	$(BIN)/jupyter lab notebooks/

book: $(STAMP)
	$(BIN)/python docs/build_book.py --out out/book

clean:
	rm -rf $(VENV) out
