# phonglab: `make demo` (set-up included) renders the demo; `make test` runs the tests.
VENV  := .venv
BIN   := $(VENV)/bin
STAMP := $(VENV)/.phonglab-installed
PYTEST_ARGS ?=
# The default tier runs on every core (pytest-xdist); PYTEST_WORKERS=0 runs it in one process.
PYTEST_WORKERS ?= auto
# The tests keep Python's bytecode (__pycache__, git-ignored) even where the environment says
# not to (PYTHONDONTWRITEBYTECODE=1, as container images set it): otherwise both workers'
# collection and every test's `python -m phonglab` child compile phonglab and the tests from
# source again, each time (a fresh clone's warm `make test`: 173 s with it set, BENCHMARKS.md).
PYTEST := PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest

.PHONY: setup demo test test-slow test-all bench check clean classic-figure docs docs-setup

$(STAMP): pyproject.toml constraints.txt scripts/setup.sh
	bash scripts/setup.sh
	@touch $(STAMP)

setup: $(STAMP)

demo: setup
	$(BIN)/phonglab render cornell_phong --spp 256 -o out/demo.exr

test: setup
	$(PYTEST) -m "not slow" -n $(PYTEST_WORKERS) $(PYTEST_ARGS)

test-slow: setup
	$(PYTEST) -m slow $(PYTEST_ARGS)

test-all: setup
	$(PYTEST) $(PYTEST_ARGS)

# Regenerates BENCHMARKS.md and docs/bench/ (CSV + PNG) from a fresh full run, after a timed
# --quick run whose wall time the report quotes. About 28 minutes on 2 quiet cores with the
# references cached (.bench_cache/references), about 42 with an empty cache; the planner's 512²
# rows are apart (make bench-planner-512), shown in BENCHMARKS.md with their date.
bench: setup
	$(BIN)/phonglab bench --quick --fresh --no-progress --out out/bench-quick
	$(BIN)/python scripts/planner_bench.py --res 128 256 --repeats 3 --out docs/bench/planner.json
	$(BIN)/python -m phonglab.bench.fit_timing --repeats 5 --out docs/bench/fit.json
	$(BIN)/python scripts/validate_timing.py --repeats 3 --json docs/bench/validate.json
	$(BIN)/phonglab bench --fresh --out docs/bench --markdown BENCHMARKS.md --quick-run out/bench-quick/run.json

# docs/classic_model.md's figure: whitted graphics vs whitted radiance vs path (~10 s).
classic-figure: setup
	$(BIN)/phonglab compare-models exponent_series --spp 32 --path-spp 512 -o out/compare_exponent_series
	cp out/compare_exponent_series/figure.png docs/img/exponent_series_compare.png

check: setup
	$(BIN)/phonglab check --json out/checks.json

# The docs site (docs/conf.py: Sphinx, MyST, the notebooks as stored, the command reference from
# the argparse parsers, the API reference from the docstrings) into build/docs/, every warning
# an error. docs-setup installs the `docs` extra into .venv when Sphinx is missing.
DOCS_IMPORTS := sphinx, myst_parser, myst_nb, sphinxarg, furo
docs-setup: setup
	@$(BIN)/python -c "import $(DOCS_IMPORTS)" 2>/dev/null || \
		$(BIN)/python -m pip install -q -c constraints.txt -e ".[docs]"

docs: docs-setup
	$(BIN)/sphinx-build -W --keep-going -b html docs build/docs

clean:
	rm -rf out .pytest_cache build src/*.egg-info

# The figures docs/notebooks.md shows (one per notebook), from phonglab.figures.
.PHONY: notebook-figures
notebook-figures: setup
	$(BIN)/python -m phonglab.figures docs/img

# Planner: planned vs default configuration at equal error (docs/planner.md); the 256² row
# takes ~20 min on 2 loaded cores (its 1024-spp references are cached after the first run).
bench-planner: setup
	$(BIN)/python scripts/planner_bench.py --res 128 256 --repeats 5

# The planner's 512² rows (issue 39), kept apart from `make bench` (which they would take past
# 30 min): docs/bench/planner-512.json, which BENCHMARKS.md shows with its date. About 75 min
# on 2 quiet cores with an empty reference cache (1024- to 32768-spp references, ~40 min of it;
# measured 2026-12-06); PLANNER_SCENES=... reruns some scenes and keeps the other rows.
PLANNER_SCENES ?=
.PHONY: bench-planner-512
bench-planner-512: setup
	$(BIN)/python scripts/planner_bench.py --res 512 --repeats 3 --merge --out docs/bench/planner-512.json $(PLANNER_SCENES)

# The fast tier as a new user meets it: `make test` in a fresh clone of HEAD, cold (empty HOME:
# no Dr.Jit kernel cache) and twice warm (docs/bench/fast_tier.json; ~10 min, quiet machine).
.PHONY: fast-tier-timing
fast-tier-timing: setup
	$(BIN)/python scripts/fast_tier_timing.py --warm 2 --own-home 1 --json docs/bench/fast_tier.json

# Where an adaptive render's time goes against mi.render at its samples, per oracle scene of
# the bench (docs/adaptive.md, issue 39): docs/bench/adaptive_cost.json (~2 min, quiet machine).
.PHONY: adaptive-cost
adaptive-cost: setup
	$(BIN)/python scripts/adaptive_cost.py --seeds 3 --json docs/bench/adaptive_cost.json

# The oracle rows at 128², 256² and 512² with that decomposition, 3 seeds each (issue 53,
# docs/adaptive.md): docs/bench/adaptive_oracle.json, rendered into BENCHMARKS.md by make bench.
# References and oracle maps first (42 min on 2 busy cores with an empty reference cache; resumed
# from out/adaptive_oracle/prepared.json), then it waits for a load average below 1.5 and times
# every row in one go (27 min on 2 quiet cores, measured 2026-12-07).
.PHONY: adaptive-oracle
adaptive-oracle: setup
	$(BIN)/python scripts/adaptive_oracle.py --seeds 3 --json docs/bench/adaptive_oracle.json

# bench --quick and validate --all-builtins --quick serially vs on a 2-process LocalCluster
# (alternating, ~6 min), phonglab.parallel's per-job overhead and the expected time on N
# machines: docs/bench/cluster.json, rendered into BENCHMARKS.md (docs/cluster.md).
.PHONY: bench-cluster
bench-cluster: setup
	$(BIN)/python scripts/cluster_bench.py --workers 2 --out docs/bench/cluster.json

# docs/fitting.md's table: phong fitted to Beckmann/GGX roughconductor and roughplastic (~20 s).
.PHONY: fitting-table
fitting-table: setup
	$(BIN)/python -m phonglab.fit.table --json docs/fitting.json --markdown docs/fitting.md

# phonglab validate: false-failure rate of the correct plugins over 20 seeds (~5 min, docs/validate.md).
.PHONY: validate-false-failures
validate-false-failures: setup
	$(BIN)/python scripts/false_failures.py --seeds 20

# Every kind's conformance table (phonglab.validate.registry.KINDS, each its catalogue part):
# the built-in plugins of Mitsuba 3.9.1 validated, written to the kind's docs/conformance*.md
# and the JSON beside it.  Each table runs its cases through their parameter sweep or at their
# given points as it says (the BSDF table's 63 cases stay at their given points: through the
# sweep at default sizes they take over an hour on 2 cores; its sweep is run at --quick,
# scripts/conformance.py --kind bsdf --sweep --quick, and what it found is in docs/validate.md).
# CONFORMANCE_ARGS=--quick for the fast sizes.  Each table resumes from its .partial.jsonl.
.PHONY: conformance
conformance: setup
	$(BIN)/python scripts/conformance.py --all-kinds $(CONFORMANCE_ARGS)
