# Entry points; everything goes through tools/ so that there is one set-up path.
# Extra arguments: make test ARGS='-k procrustes -x'; make ch5 ARGS='--out runs/mine'
# Durations (2 cores) are in docs/performance.md; every target writes into runs/<name>/.
ARGS ?=
RUN = bash tools/setup.sh && bash
PY = bash tools/setup.sh && bash -c 'source tools/env.sh && exec python "$$@"' python
.PHONY: setup demo test bench ch3 ch3-graph ch4 ch5 ch5-seed0 ch6 ch6-nao-poppy ch6-nao-poppy-zup multi-host

setup:
	bash tools/setup.sh

demo:        # a few minutes: chapter 5 in small over the node graph, into runs/demo/
	bash tools/run_default.sh $(ARGS)

test:
	bash tools/run_tests.sh $(ARGS)

bench: setup
	bash -c 'source tools/env.sh && exec python -m bench.table "$$@"' bench $(ARGS)

ch3:         # thesis Fig. 3-6 and 3-8 (library only), into runs/two_link_fk/
	$(PY) scenarios/two_link_fk/run_two_link_fk.py $(ARGS)

ch3-graph:   # thesis §3.6 over the node graph, into runs/two_link_graph/
	$(RUN) scenarios/two_link_graph/run.sh $(ARGS)

ch4:         # thesis §4.5 over the node graph, into runs/lfd/
	$(RUN) scenarios/lfd/run.sh $(ARGS)

ch5:         # thesis §5.5.3, 10 seeds over the node graph, into runs/inverse_dynamics/: each seed a task
             # of a local Dask cluster on every core (ARGS='--address tcp://HOST:8786': a cluster's)
	$(PY) -m lpa_transfer.sweeps graph ch5 $(ARGS)

ch5-seed0:   # the same for seed 0 only
	$(RUN) scenarios/inverse_dynamics/run.sh --override scenarios/inverse_dynamics/one_seed.yaml $(ARGS)

ch6:         # thesis §6.5.1 (Table 6.1), 10 seeds, into runs/goal_babbling/
	$(RUN) scenarios/goal_babbling/run.sh $(ARGS)

ch6-nao-poppy:   # thesis §6.5.2 (Nao -> Poppy), 10 seeds, into runs/nao_poppy/
	$(RUN) scenarios/goal_babbling/run.sh --config scenarios/goal_babbling/nao_poppy.yaml --out runs/nao_poppy $(ARGS)

ch6-nao-poppy-zup:   # §6.5.2 in the thesis' z-up scene, 10 seeds, into runs/nao_poppy_zup/
	$(RUN) scenarios/goal_babbling/run.sh --config scenarios/goal_babbling/nao_poppy.yaml --override scenarios/goal_babbling/nao_poppy_zup.yaml --out runs/nao_poppy_zup $(ARGS)

multi-host:  # the 2-link graph over three network namespaces (root), into runs/multi_host/
	$(RUN) scenarios/multi_host/run.sh --config scenarios/two_link_graph/config.yaml --out runs/multi_host $(ARGS)
