# Entry points; everything goes through tools/ so that there is one set-up path.
# Extra arguments: make test ARGS='-k procrustes -x'
ARGS ?=
.PHONY: setup demo test bench

setup:
	bash tools/setup.sh

demo:
	bash tools/run_default.sh $(ARGS)

test:
	bash tools/run_tests.sh $(ARGS)

bench: setup
	bash -c 'source tools/env.sh && exec python -m bench.bench_lpa "$$@"' bench $(ARGS)
