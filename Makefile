# gpo: `make test` checks everything, `make demo` runs the main job into out/, `make lab` opens the notebooks.
# `make book` builds the executed notebooks, without running them, into a Jupyter Book (docs/book/): out/book/index.html;
# it builds and reads offline, its formulas rendered by the MathJax of the pinned PyPI package jupyter-server-mathjax.
# `make test-browser` runs every chapter's panels in JupyterLab in Debian's Chromium (installed with apt when missing); `make
# test` includes it.
# Each creates .venv from environment.txt first when it is missing or environment.txt has changed.

PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.environment.stamp
CHROMIUM := /usr/bin/chromium
SUDO := $(if $(filter 0,$(shell id -u)),,sudo)
# runs a phase of `make test` and prints its time into the log (venv, recordings, tables, wheel, pytest)
PHASE := .ci/phase

.PHONY: test test-browser recordings tables wheel demo lab book env clean

# two jobs at a time: Chromium is installed (apt, mostly waiting on the network) while the venv is made and the
# recordings render; the phases that need each other still wait for each other
MAKEFLAGS += --jobs=2

env: $(STAMP)

# uv (its pin in environment.txt) installs the pinned packages: 38 s from an empty download cache where pip took 1 min
# 29 s with a full one, the same packages; everything is compiled once here (gpo's own modules in 0.2 s): where
# PYTHONDONTWRITEBYTECODE is set, as in CI, every process of the checks would otherwise compile what it imports
UV := $(BIN)/uv pip install --python $(BIN)/python --quiet
$(STAMP): environment.txt pyproject.toml
	rm -rf $(VENV)
	$(PHASE) venv sh -c '$(PYTHON) -m venv $(VENV) && \
		$(BIN)/python -m pip install --quiet --disable-pip-version-check $$(grep "^uv==" environment.txt) && \
		$(UV) --compile-bytecode -r environment.txt && \
		$(UV) --no-deps --no-build-isolation -e . && \
		$(BIN)/python -m compileall -q gpo'
	touch $(STAMP)

$(CHROMIUM):
	$(SUDO) apt-get update -qq
	$(SUDO) DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium

# The checks run two processes on the two cores; OpenCV's and OpenBLAS's own threads on top of them only cost processor
# time (rendering takes 17 % less, the tests 7 % less, on one thread each)
recordings tables wheel test test-browser: export OPENCV_FOR_THREADS_NUM = 1
recordings tables wheel test test-browser: export OPENBLAS_NUM_THREADS = 1
recordings tables wheel test test-browser: export OMP_NUM_THREADS = 1

# the simulated recordings that tests and chapters read, made once into the cache, longest first on two processes
recordings: $(STAMP)
	$(PHASE) recordings $(BIN)/python -m gpo recording --jobs 2 long3 long1 long2 sample \
		paper2-iv paper2-viii short2 short3 short1 \
		downward-wood downward-raised downward-industrial glossy test

# Table 4's floor runs (chapter 09 reads them), Table 3's (chapter 05), chapter 08's floor runs and lab chapter A's
# glossy ones (with short1's, with and without the check), kept in the cache: six jobs of a minute or two, longest
# first, two at a time. The second paper's experiments I-IX and the ablation from its published method (full-image
# SIFT: about half an hour on one core) are left to benchmarks/second_paper.py, whose saved rows lab C prints
TABLE_JOBS := "gpo table4 long3" "gpo table4 long1" "gpo table4 long2" "gpo table2 floors" "gpo.book.lab_a_glossy_floors" \
	"gpo table3"
tables: recordings
	$(PHASE) tables sh -c 'printf "%s\n" $(TABLE_JOBS) | xargs -P 2 -L 1 $(BIN)/python -m > /dev/null'

# gpo as a user installs it (.ci/wheel): the wheel, in a new environment with the newest releases pyproject.toml allows
# (not environment.txt's pins), runs its command line on the sample recording from outside the checkout; half a
# minute, beside `tables`
wheel: recordings
	$(PHASE) wheel .ci/wheel $(BIN)/uv $(PYTHON)

# the checks whose printed numbers a floating-point path could change run again on two other paths of this machine
# (.ci/fp-path: avx2, then sse4): the chapters under nbval (the mounts chapters 01 and 10 measure among them), and the
# calibration, fusion and papers' tables tests. They read the recordings and kept runs that the machine's own path made
# (cache keys do not depend on the path). Lab B prints saved benchmark results, and lab E runs every path itself, each
# in a process of its own: they run once, in the pytest phase
FP_NOTEBOOKS := $(filter-out notebooks/B_% notebooks/E_%,$(wildcard notebooks/*.ipynb))
FP_CHECKS := $(FP_NOTEBOOKS) tests/test_calibrate.py tests/test_calibrate_models.py tests/test_camera_fit.py \
	tests/test_fusion.py tests/test_fusion_pipeline.py tests/test_table1.py tests/test_table3_metric.py \
	tests/test_table4.py tests/test_paper_table2.py tests/test_paper_equations.py
PYTEST := $(BIN)/python -m pytest -p no:cacheprovider -n 2 --dist loadfile

# two workers (pytest-xdist), each test file on one of them: a notebook's cells share one kernel; the log lists the
# 25 slowest tests, where the time goes. Then the other paths, one after the other (run side by side, the three
# phases take 10 min 31 s where one after the other they take 10 min 10 s)
test: $(STAMP) $(CHROMIUM) recordings tables wheel
	$(BIN)/ruff check .
	$(PHASE) pytest $(PYTEST) --durations=25
	$(PHASE) fp-avx2 .ci/fp-path avx2 $(PYTEST) -q $(FP_CHECKS)
	$(PHASE) fp-sse4 .ci/fp-path sse4 $(PYTEST) -q $(FP_CHECKS)

test-browser: $(STAMP) $(CHROMIUM) recordings
	$(BIN)/python -m pytest -p no:cacheprovider tests/browser

demo: $(STAMP)
	$(BIN)/python -m gpo demo --out out

lab: $(STAMP)
	$(BIN)/jupyter lab notebooks/

book: $(STAMP)
	$(BIN)/python docs/build_book.py --out out/book

clean:
	rm -rf $(VENV) out
