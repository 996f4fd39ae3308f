# The two set-up commands of the README. Both install what a fresh Debian machine lacks first.
SHELL := /bin/bash
CARGO ?= cargo
DEMO_OUT ?= out/demo

.PHONY: deps demo test build net pytest wheel bench-python bench-cluster docs test-sumo-latest test-cluster

# Which SUMO bkpbs builds and runs against: `apt`, Debian's package (the default), or `pip`, the
# eclipse-sumo wheel of version $(SUMO_PIP_VERSION) from PyPI, installed into the virtualenv
# $(VENV). A pip build has its own target directory (target/sumo-pip), so both can stand side by
# side, and runs with the wheel's SUMO_HOME and programs (sumo, netconvert, sumo-gui) first on PATH.
SUMO ?= apt
SUMO_PIP_VERSION ?= 1.28.0
PYTHON ?= python3
VENV ?= .venv
# The wheel's SUMO_HOME inside the virtualenv (site-packages/sumo).
PIP_SUMO_HOME := $(abspath $(VENV))/lib/python$(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)/site-packages/sumo
ifeq ($(SUMO),pip)
export SUMO_HOME := $(PIP_SUMO_HOME)
export CARGO_TARGET_DIR := $(abspath target/sumo-pip)
export PATH := $(SUMO_HOME)/bin:$(PATH)
# The other SUMO, for the test that a run against it is refused: Debian's.
export BKPBS_OTHER_SUMO_LIB ?= $(dir $(firstword $(wildcard /usr/lib/*/libsumocpp.so)))
else ifeq ($(SUMO),apt)
export BKPBS_OTHER_SUMO_LIB ?= $(PIP_SUMO_HOME)/lib64
else
$(error SUMO=$(SUMO): choose apt (Debian's package, the default) or pip (the eclipse-sumo wheel))
endif
TARGET_DIR := $(abspath $(or $(CARGO_TARGET_DIR),target))
# The SUMO version the bkpbs binary $(1) is built against (`bkpbs --version`).
sumo_of = $$($(1) --version | sed -n 's/.*SUMO \([0-9.]*\)).*/\1/p')

deps:
	@bash scripts/ensure-deps.sh
ifeq ($(SUMO),pip)
	@VENV=$(VENV) SUMO_PIP_VERSION=$(SUMO_PIP_VERSION) bash scripts/ensure-python.sh sumo
endif

build: deps
	$(CARGO) build --release --quiet

# The main job: a small campaign of every planner (α 0.4 / 0.8, λ 2500 / 3000, 2 seeds, 400
# steps), started afresh, with its report tables printed.
demo: build
	rm -rf $(DEMO_OUT)
	$(TARGET_DIR)/release/bkpbs campaign --alphas 0.4,0.8 --lambdas 2500,3000 --seeds 2 --steps 400 --out $(DEMO_OUT)
	@echo "demo: CSV files in $(DEMO_OUT)/ (episodes.csv, vehicles.csv, timings.csv, failures.csv; one directory per episode under episodes/)"
	@echo "demo: tables and figures in $(DEMO_OUT)/report/ (tables.md, *.csv, collision_heatmap, delay_vs_collision, metrics_vs_alpha .png/.svg)"

# The whole suite: formatting, lints, unit and integration tests (integration tests run real SUMO).
# The Python tools and the eclipse-sumo wheel come first: the tests check that a run against a
# SUMO other than the one bkpbs was built against (the wheel's or Debian's) is refused.
test: deps
	@VENV=$(VENV) SUMO_PIP_VERSION=$(SUMO_PIP_VERSION) bash scripts/ensure-python.sh sumo tools
	@if $(CARGO) fmt --version >/dev/null 2>&1; then $(CARGO) fmt --all -- --check; else echo "test: rustfmt not installed, format check skipped"; fi
	@if $(CARGO) clippy --version >/dev/null 2>&1; then $(CARGO) clippy --quiet --all-targets -- -D warnings; else echo "test: clippy not installed, lint skipped"; fi
	$(CARGO) test --quiet
	@$(MAKE) --no-print-directory pytest

# The Python bindings (bindings/): a virtualenv $(VENV) with maturin, pytest and ray
# (scripts/ensure-python.sh) and SUMO's libsumo wheel of the version bkpbs is built against, the
# wheel built with maturin (a test build) and installed into it, then the Python
# tests (real SUMO, a local Ray), which compare against the CLI binary `cargo test` builds.
pytest: deps
	@VENV=$(VENV) SUMO_PIP_VERSION=$(SUMO_PIP_VERSION) bash scripts/ensure-python.sh sumo tools
	$(CARGO) build --quiet --profile test --bin bkpbs
	@VENV=$(VENV) LIBSUMO_VERSION=$(call sumo_of,$(TARGET_DIR)/debug/bkpbs) bash scripts/ensure-python.sh libsumo
	rm -rf $(TARGET_DIR)/wheels
	$(VENV)/bin/maturin build --quiet -m bindings/Cargo.toml --profile dev --out $(TARGET_DIR)/wheels
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps $(TARGET_DIR)/wheels/bkpbs-*.whl
	BKPBS_BIN=$(TARGET_DIR)/debug/bkpbs $(VENV)/bin/python -m pytest -q -p no:cacheprovider $(PYTESTS)

# The Python package as a user installs it (bindings/README.md): a release wheel in
# $(TARGET_DIR)/wheels-release, installed into $(VENV) beside SUMO's libsumo wheel of the version
# bkpbs is built against, so a TraCI loop there runs SUMO in-process at full speed. (`make
# pytest` installs its quicker-to-build test wheel over it.)
wheel: build
	@VENV=$(VENV) bash scripts/ensure-python.sh wheel
	rm -rf $(TARGET_DIR)/wheels-release
	$(VENV)/bin/maturin build --quiet --release -m bindings/Cargo.toml --out $(TARGET_DIR)/wheels-release
	$(VENV)/bin/python -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps $(TARGET_DIR)/wheels-release/bkpbs-*.whl
	@VENV=$(VENV) LIBSUMO_VERSION=$(call sumo_of,$(TARGET_DIR)/release/bkpbs) bash scripts/ensure-python.sh libsumo
	@echo "wheel: bkpbs (release) and libsumo installed into $(VENV)"

# A TraCI loop of your own from $(VENV) (libsumo in-process, and traci) against the CLI on the
# same scenario, side by side (examples/loop_speed.py): wall times, ratios, identical files.
bench-python: wheel
	$(VENV)/bin/python examples/loop_speed.py --bin $(TARGET_DIR)/release/bkpbs $(BENCH_ARGS)

# How a campaign scales with Ray nodes (bindings/tests/bench_cluster.py): the same grid on a
# cluster of 1 and of 2 worker nodes of one CPU each, nodes that do not see the campaign's files.
# Needs root and unshare.
bench-cluster: wheel
	@VENV=$(VENV) bash scripts/ensure-python.sh tools
	cd bindings/tests && $(abspath $(VENV))/bin/python bench_cluster.py $(BENCH_ARGS)

# Which Python tests `make pytest` runs.
PYTESTS ?= bindings/tests

# The Ray cluster test alone (bindings/tests/test_ray_cluster.py, part of `make pytest`, about
# 50 s): a head node without CPUs and worker nodes in mount namespaces of their own, which do
# not see the campaign's files, run campaigns whose files must travel through Ray; one node is
# killed mid-campaign. Needs root and unshare (skipped otherwise).
test-cluster:
	@$(MAKE) --no-print-directory pytest PYTESTS=bindings/tests/test_ray_cluster.py

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

# The suite against today's SUMO as well: `make test SUMO=pip` (the eclipse-sumo wheel), beside
# the default build. Not part of `make test` (see the guide's installation chapter).
test-sumo-latest:
	@$(MAKE) --no-print-directory test SUMO=pip
