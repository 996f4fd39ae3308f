# The two set-up commands of the README. Both install what a fresh Debian machine lacks first.
SHELL := /bin/bash
CARGO ?= cargo
DEMO_OUT ?= out/demo

.PHONY: deps demo test build net pytest docs

deps:
	@bash scripts/ensure-deps.sh

build: deps
	$(CARGO) build --release --quiet

# The main job: a small campaign of every planner (α 0.4 / 0.8, λ 2500 / 3000, 2 seeds, 400
# steps), started afresh, with its report tables printed.
demo: build
	rm -rf $(DEMO_OUT)
	./target/release/bkpbs campaign --alphas 0.4,0.8 --lambdas 2500,3000 --seeds 2 --steps 400 --out $(DEMO_OUT)
	@echo "demo: CSV files in $(DEMO_OUT)/ (episodes.csv, vehicles.csv, timings.csv, failures.csv; one directory per episode under episodes/)"
	@echo "demo: tables and figures in $(DEMO_OUT)/report/ (tables.md, *.csv, collision_heatmap, delay_vs_collision, metrics_vs_alpha .png/.svg)"

# The whole suite: formatting, lints, unit and integration tests (integration tests run real SUMO).
test: deps
	@if $(CARGO) fmt --version >/dev/null 2>&1; then $(CARGO) fmt --all -- --check; else echo "test: rustfmt not installed, format check skipped"; fi
	@if $(CARGO) clippy --version >/dev/null 2>&1; then $(CARGO) clippy --quiet --all-targets -- -D warnings; else echo "test: clippy not installed, lint skipped"; fi
	$(CARGO) test --quiet
	@$(MAKE) --no-print-directory pytest

# The Python bindings (bindings/): a virtualenv $(VENV) with maturin, pytest and ray
# (scripts/ensure-python.sh), the wheel built with maturin and installed into it, then the Python
# tests (real SUMO, a local Ray), which compare against the CLI binary `cargo test` builds.
VENV ?= .venv
TARGET_DIR := $(abspath $(or $(CARGO_TARGET_DIR),target))
pytest: deps
	@VENV=$(VENV) bash scripts/ensure-python.sh
	$(CARGO) build --quiet --profile test --bin bkpbs
	rm -rf $(TARGET_DIR)/wheels
	$(VENV)/bin/maturin build --quiet -m bindings/Cargo.toml --profile dev --out $(TARGET_DIR)/wheels
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps $(TARGET_DIR)/wheels/bkpbs-*.whl
	BKPBS_BIN=$(TARGET_DIR)/debug/bkpbs $(VENV)/bin/python -m pytest -q -p no:cacheprovider bindings/tests

# Regenerates the networks sumo_net/*.net.xml (merge, three-lane, corridor) from their plain XML
# sources; an unchanged network keeps its file (see sumo_net/README.md).
net: deps
	bash sumo_net/build_net.sh

# The user guide (docs/, an mdBook) rendered into docs/book/, mdbook installed first if missing;
# then the API documentation, with rustdoc's warnings as errors.
MDBOOK ?= $(shell command -v mdbook 2>/dev/null || echo $(or $(CARGO_HOME),$(HOME)/.cargo)/bin/mdbook)
docs:
	@if ! [ -x "$(MDBOOK)" ]; then $(CARGO) install mdbook --locked; fi
	$(MDBOOK) build docs
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps
