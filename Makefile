# The two set-up commands of the README. Both install what a fresh Debian machine lacks first.
SHELL := /bin/bash
CARGO ?= cargo
DEMO_OUT ?= out/demo

.PHONY: deps demo test build net

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
	@echo "demo: tables and figures in $(DEMO_OUT)/report/ (tables.md, *.csv, collision_heatmap.png/.svg, delay_vs_collision.png/.svg)"

# The whole suite: formatting, lints, unit and integration tests (integration tests run real SUMO).
test: deps
	@if $(CARGO) fmt --version >/dev/null 2>&1; then $(CARGO) fmt --all -- --check; else echo "test: rustfmt not installed, format check skipped"; fi
	@if $(CARGO) clippy --version >/dev/null 2>&1; then $(CARGO) clippy --quiet --all-targets -- -D warnings; else echo "test: clippy not installed, lint skipped"; fi
	$(CARGO) test --quiet

# Regenerates sumo_net/merge.net.xml from its plain XML sources.
net: deps
	bash sumo_net/build_net.sh
