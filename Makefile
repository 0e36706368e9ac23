# EmoGen: `make demo` sets everything up and runs the main job; `make test` runs every check,
# `make check` the fast tier of them (while working).
SHELL := /bin/bash
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
# The ICT-FaceKit model: $EMOGEN_MODEL, else ../shared beside the clone, else the user cache
# (`emogen model fetch` installs it there).
SHARED_MODEL := $(abspath ../shared/ict-facekit/FaceXModel)
EMOGEN_MODEL ?= $(if $(wildcard $(SHARED_MODEL)),$(SHARED_MODEL),)
export EMOGEN_MODEL
OUT ?= out
VIEWER := src/emogen/web/static/build/.built
PLUGIN_DIR := packages/jspsych-plugin-emogen
PLUGIN := $(PLUGIN_DIR)/dist/.built

# The tests run spread over the CPU's cores (pytest-xdist; TEST_WORKERS=0: in one process), a
# test file at a time per worker: a module's fixtures, servers and browser stay in one process.
TEST_WORKERS ?= auto
PYTEST_OPTIONS := -q -n $(TEST_WORKERS) --dist loadfile

.PHONY: setup system test check lint demo demo-analyse bench clean

setup: system $(VENV)/.installed node_modules/.installed $(VIEWER) $(PLUGIN)

system:
	bash scripts/install-system-deps.sh

$(VENV)/.installed: pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $@

node_modules/.installed: package.json package-lock.json
	npm ci --no-audit --no-fund --loglevel=error
	touch $@

$(VIEWER): node_modules/.installed $(wildcard src/emogen/web/viewer/* src/emogen/web/build.mjs src/emogen/web/viewer_entry.js src/emogen/render/look.json src/emogen/render/shaders/*)
	npm run build
	touch $@

# The jsPsych plugin: the study page's own modules and viewer, bundled for other sites' pages.
$(PLUGIN): node_modules/.installed $(wildcard $(PLUGIN_DIR)/build.mjs $(PLUGIN_DIR)/src/* src/emogen/web/static/*.js src/emogen/web/static/tasks/* src/emogen/web/static/study.css src/emogen/web/viewer/* src/emogen/web/viewer_entry.js src/emogen/render/look.json src/emogen/render/shaders/*)
	node $(PLUGIN_DIR)/build.mjs

lint: setup
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	npx --no-install eslint .
	npx --no-install tsc -p tsconfig.json

# Everything CI runs (.ci/run): lint, types, the JavaScript tests and every pytest test.
# The CPU and BLAS kernel first: floating-point results can differ in the last bits between them.
test: lint
	$(BIN)/python scripts/platform_report.py
	node --test tests/web/js/ $(PLUGIN_DIR)/tests/
	$(BIN)/python -m pytest $(PYTEST_OPTIONS)

# The fast tier, to run while working: lint, types, the JavaScript tests and every pytest test
# not marked slow, browser or postgres (tests/tiers.py says which and why); about 3 minutes.
check: lint
	node --test tests/web/js/ $(PLUGIN_DIR)/tests/
	$(BIN)/python -m pytest $(PYTEST_OPTIONS) -m "not slow and not browser and not postgres"

demo: setup
	@if [ -z "$$EMOGEN_MODEL" ] && [ ! -d "$$($(BIN)/python -c 'from emogen.model.io.fetch import default_model_dir; print(default_model_dir())')/FaceXModel" ]; then \
		$(BIN)/emogen model fetch; fi
	$(BIN)/emogen model info | head -n 4
	$(BIN)/emogen simulate --target jawOpen=0.8 --runs 500 --seed 1 --out $(OUT)/simulation --force
	@echo "Starting the demo study (Ctrl-C stops it); open the URL it prints."
	@echo "Afterwards, 'make demo-analyse' exports what was recorded and analyses it."
	$(BIN)/emogen serve --database-url sqlite:///$(abspath $(OUT))/demo-study.sqlite

# The step after the demo: export the demo study's records, analyse them and the simulation.
demo-analyse: setup
	$(BIN)/emogen study export --database-url sqlite:///$(abspath $(OUT))/demo-study.sqlite \
		--out $(OUT)/demo-export --force
	$(BIN)/emogen analyse $(OUT)/demo-export --out $(OUT)/demo-analysis --force
	$(BIN)/emogen analyse $(OUT)/simulation --out $(OUT)/simulation-analysis --force --no-render
	@echo "Open $(OUT)/demo-analysis/index.html and $(OUT)/simulation-analysis/index.html"

bench: setup
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) node_modules .pytest_cache .mypy_cache .ruff_cache $(OUT)
