# The two set-up commands of the README. Both install what a fresh Debian machine lacks first.
SHELL := /bin/bash
CARGO ?= cargo
DEMO_OUT ?= out/demo

.PHONY: deps demo test build net

deps:
	@bash scripts/ensure-deps.sh

build: deps
	$(CARGO) build --release --quiet

# The main job: one episode of the default scenario (α = 0.5, λ = 3000 veh/h, seed 0).
demo: build
	./target/release/bkpbs episode --out $(DEMO_OUT)
	@echo "demo: CSV files in $(DEMO_OUT)/ (episode.csv, vehicles.csv, collisions.csv, timing.csv)"

# The whole suite: formatting, lints, unit and integration tests (integration tests run real SUMO).
test: deps
	@if $(CARGO) fmt --version >/dev/null 2>&1; then $(CARGO) fmt --all -- --check; else echo "test: rustfmt not installed, format check skipped"; fi
	@if $(CARGO) clippy --version >/dev/null 2>&1; then $(CARGO) clippy --quiet --all-targets -- -D warnings; else echo "test: clippy not installed, lint skipped"; fi
	$(CARGO) test --quiet

# Regenerates sumo_net/merge.net.xml from its plain XML sources.
net: deps
	bash sumo_net/build_net.sh
