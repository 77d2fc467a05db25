# Two commands do all the set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow mutants bench bench-quick docs docs-serve clean

$(STAMP): pyproject.toml
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[test,bench]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/jaxrod map --out results/demo

# Two pytest workers (pytest-xdist) taking tests one by one: CI has 2 cores, and most of the
# suite's time is single-threaded XLA compilation. TEST_WORKERS=0 runs in one process.
TEST_WORKERS ?= 2

test: $(STAMP)
	$(BIN)/python -m pytest -n $(TEST_WORKERS) --dist worksteal

test-slow: $(STAMP)
	$(BIN)/python -m pytest -m slow -n $(TEST_WORKERS) --dist worksteal

# Mutation testing (mutmut) of the physics and reporting modules against the default tests mapped
# to each (tools/mutants.py): report in results/mutation/. Reruns the groups with a module changed
# since their run (the report's stale line); GROUPS="theory friction" runs those. The held-out
# estimate of the whole engine: python tools/mutants.py --held-out 400 --seed S (a new seed each time).
mutants: $(STAMP)
	$(BIN)/pip install --quiet -e ".[mutation]"
	$(BIN)/python tools/mutants.py --changed $(GROUPS)

# Every script under benchmarks/, the quick ones first; scripts added later run after these.
BENCH_FIRST := field_throughput alternatives sweep_throughput boundary_cost field_convergence model_choice
BENCH_SCRIPTS := $(BENCH_FIRST:%=benchmarks/%.py) \
	$(filter-out $(BENCH_FIRST:%=benchmarks/%.py) benchmarks/_%,$(sort $(wildcard benchmarks/*.py)))

bench: $(STAMP)
	@set -e; for s in $(BENCH_SCRIPTS); do echo "== $$s"; $(BIN)/python $$s; done

# The same with --quick for the scripts that take it (the others run with their defaults).
bench-quick: $(STAMP)
	@set -e; for s in $(BENCH_SCRIPTS); do \
		if grep -q -- '"--quick"' $$s; then echo "== $$s --quick"; $(BIN)/python $$s --quick; \
		else echo "== $$s"; $(BIN)/python $$s; fi; \
	done

# The documentation site (mkdocs.yml, docs/): built into site/ with --strict (a broken link or
# cross-reference fails), or served with live reload at http://127.0.0.1:8000. The test extra
# installs MkDocs and its plugins (the `docs` extra alone: pip install -e ".[docs]").
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

docs-serve: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs serve

clean:
	rm -rf $(VENV) results/demo site mutants
