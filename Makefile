# EmoGen: `make demo` sets everything up and runs the main job; `make test` runs every check.
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

.PHONY: setup test lint demo bench clean

setup: $(VENV)/.installed node_modules/.installed

$(VENV)/.installed: pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $@

node_modules/.installed: package.json package-lock.json
	npm ci --no-audit --no-fund --loglevel=error
	touch $@

lint: setup
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint
	$(BIN)/python -m pytest -q

demo: setup
	@if [ -z "$$EMOGEN_MODEL" ] && [ ! -d "$$($(BIN)/python -c 'from emogen.model.io.fetch import default_model_dir; print(default_model_dir())')/FaceXModel" ]; then \
		$(BIN)/emogen model fetch; fi
	$(BIN)/emogen model info
	mkdir -p $(OUT)
	$(BIN)/emogen model export --out $(OUT)/ict-face.glb
	$(BIN)/emogen model export --face --weight jawOpen=0.4 --weight mouthSmile=0.8 --weight cheekSquint=0.6 --identity female --out $(OUT)/smile-female.obj
	$(BIN)/emogen simulate --target jawOpen=0.8 --runs 500 --seed 1 --out $(OUT)/simulation
	$(BIN)/python benchmarks/run.py

bench: setup
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) node_modules .pytest_cache .mypy_cache .ruff_cache $(OUT)
