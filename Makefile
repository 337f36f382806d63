# The two commands of the README:
#   make reproduce   set up everything and run the whole pipeline (dvc repro)
#   make test        set up everything and run the test suite (what CI runs)
# Both are idempotent: the virtual environment is built once and reused, and they work from a
# shell in which no environment is active.  The pipeline's stages start .venv/bin/python
# themselves (conf/pipeline/full.yaml), so nothing here or in dvc.yaml depends on the caller's PATH.
#
# Other targets:
#   make reproduce PROFILE=quick   the same dvc.yaml on the small profile, in a scratch copy
#                                  ($(QUICK_DIR)); the workspace's own outputs are not touched
#   make mlflow                    serve the workspace's MLflow runs on http://127.0.0.1:$(MLFLOW_PORT); open the
#                                  runs table it prints, http://127.0.0.1:$(MLFLOW_PORT)/#/experiments/<id>/runs
#                                  ?viewStateShareKey=summary: one row per model (accuracy, training time,
#                                  speed-up); MLflow's home page is its GenAI overview
#   make lint / test-slow / bench
#   make time-tests                make setup + make test in a fresh clone of HEAD from a plain shell, timed:
#                                  reports/test_timing.json (the README's commands table)
#   make ross-peer                 ROSS 3.1 (external peer, its own .venv-ross, Python 3.13) vs ours:
#                                  benchmarks/bench_ross_peer.py, then the ROSS adapter's report (bench_ross_adapter.py)
#   make ross-env / test-ross      build .venv-ross only / run the ROSS adapter's tests in it
#   make variants                  the long variants outside the pipeline's budget, each to a committed report:
#                                  universal-train, jfo-surrogate-seeds, train-time-ranking, paper-scale-ablation
#                                  (below, beside their targets)
#   make universal-weights         copy the trained universal surrogate (models/universal) into the package
#   make kernel-source             the generated kernels of the universal surrogate, as Python files to read:
#                                  build/kernels/ (fluidfilm.surrogate.kernels.write_kernel_sources)
#   make train-time-ci             the training-time study at 3x the pipeline's subsample (12,000 per
#                                  seed) until its 95 % interval is +-10 points (hours here:
#                                  docs/paper_experiment.md): reports/train_time_ci.json
#   make train-time-full-scale     one run per structure on all 4.5 M samples (Adam, same stopping rule):
#                                  reports/train_time_full_scale.json
#   make paper-scale-curve         the paper's networks at 160 k, 640 k and 2.56 M samples (LM, hours):
#                                  reports/paper_scale_curve.json (resumes where it stopped)
#   make paper-full-scale          the paper's networks on all 4.5 M samples (LM; the split's eps > 0.7
#                                  network to LM_BUDGET_S, then Adam): reports/paper_full_scale.json
PYTHON      ?= python3
VENV        := .venv
PY          := $(VENV)/bin/python
STAMP       := $(VENV)/.installed
PROFILE     ?= full
QUICK_DIR   ?= build/quick
MLFLOW_PORT ?= 5000

.PHONY: setup reproduce test test-slow lint bench mlflow dvc-remote dvc-cache clean-venv

setup: $(STAMP)

# torch first and pinned: 2.13.0 is the CPU build that lies on disk here;
# any other spec would pull gigabytes of CUDA wheels. Then the project with every extra the workspace uses
# (`all` = workspace, learn, test; `pip install fluidfilm` alone is the lean library core).
# The environment is created once; a changed pyproject.toml reinstalls into it. (Re-running `venv`
# over an existing one with another `python3` on PATH would mix two interpreters' standard libraries.)
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --upgrade pip
	$(PY) -m pip install --quiet --disable-pip-version-check torch==2.13.0
	$(PY) -m pip install --quiet --disable-pip-version-check -e ".[all]"
	touch $(STAMP)

reproduce: setup
ifeq ($(PROFILE),full)
	$(PY) -m fluidfilm.workflow.pipeline run
else
	$(PY) -m fluidfilm.workflow.pipeline run --profile $(PROFILE) --workdir $(QUICK_DIR)
endif

test: setup
	$(PY) -m pytest

# lint and type check: ruff (rules in pyproject.toml) and mypy on src/ (the force-model contract)
lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

test-slow: setup
	$(PY) -m pytest -m slow
	@if test -x $(ROSS_VENV)/bin/python; then $(MAKE) test-ross; else echo "test-slow: no $(ROSS_VENV) (make ross-env builds it): the ROSS adapter's tests were skipped"; fi

bench: setup
	$(PY) benchmarks/bench_solver.py
	$(PY) benchmarks/bench_swift_stieber.py
	$(PY) benchmarks/bench_swift_stieber_scaling.py
	$(PY) benchmarks/bench_rotor.py
	$(PY) benchmarks/bench_conical.py
	$(PY) benchmarks/bench_training_step.py
	$(PY) benchmarks/bench_surrogate_kernels.py
	$(PY) benchmarks/probe_thread_spread.py
	$(PY) benchmarks/bench_universal_cost.py
	$(PY) benchmarks/bench_tanh64.py
	$(PY) benchmarks/bench_jfo.py
	$(PY) benchmarks/bench_kernel_cache.py

.PHONY: time-tests
time-tests: setup
	$(PY) benchmarks/time_fresh_clone.py
	$(PY) -m fluidfilm.reporting.readme

mlflow: setup
	$(PY) -m fluidfilm.workflow.pipeline serve --port $(MLFLOW_PORT)

# Sharing outputs in a team (there is no default remote: `make reproduce` regenerates everything).
#   make dvc-remote REMOTE=/shared/fluidfilm-dvc   (any DVC remote URL: s3://..., ssh://...), then
#   .venv/bin/dvc push   on the machine that ran the pipeline, .venv/bin/dvc pull   elsewhere
#   make dvc-cache CACHE=/shared/dvc-cache         one cache for several clones on the same machine/NFS
# Both write .dvc/config.local (not committed), so each user chooses their own.
dvc-remote: setup
	@test -n "$(REMOTE)" || { echo "usage: make dvc-remote REMOTE=<path or URL>"; exit 2; }
	$(VENV)/bin/dvc remote add --local --force --default team "$(REMOTE)"

dvc-cache: setup
	@test -n "$(CACHE)" || { echo "usage: make dvc-cache CACHE=<path>"; exit 2; }
	$(VENV)/bin/dvc cache dir --local "$(CACHE)"
	$(VENV)/bin/dvc config --local cache.shared group
	$(VENV)/bin/dvc config --local cache.type "reflink,symlink,hardlink,copy"

clean-venv:
	rm -rf $(VENV)

# Optional external peer and host: ROSS 3.1 (ross-rotordynamics, Python >= 3.13) in its own environment,
# .venv-ross, never a dependency of the workspace. It is built from benchmarks/ross_peer_constraints.txt (the
# versions it was measured with, pytest included) and rebuilt when that file changes; fluidfilm goes into it
# editable and without its dependencies (the core's numpy, scipy, numba and pandas are among those pins). A ROSS
# user's own environment needs none of this: `pip install "fluidfilm[ross]"` on Python >= 3.13.
# The base interpreter: ROSS_BASE_PY if given, else pyenv's 3.13, else python3.13 on PATH.
ROSS_VENV       ?= .venv-ross
ROSS_BASE_PY    ?= $(firstword $(wildcard $(HOME)/.pyenv/versions/3.13*/bin/python3.13) $(shell command -v python3.13 2>/dev/null))
ROSS_PINS       := benchmarks/ross_peer_constraints.txt
ROSS_STAMP      := $(ROSS_VENV)/.installed
ROSS_FF_STAMP   := $(ROSS_VENV)/.fluidfilm
# The pipeline's `train_time` stage runs the study on 4,000 samples per seed (conf/train_time.yaml) to a
# +-10-point interval; this runs the same study (same data, protocol and seeds) at three times the subsample
# until its interval reaches the same target: does the result hold at a larger size? Interrupted, it
# resumes at the next seed (cache/train_time_ci).
# The long variants, outside `make reproduce` (its budget is 60 min on the project's two cores), each writing a
# committed report that the pipeline's report and the README read (with the machine and date it ran on):
#   universal-train       the universal surrogate's dataset and training (~15 min): models/universal, and
#                         reports/universal_train.json: are they the shipped weights, bit for bit?
#   jfo-surrogate-seeds   the JFO surrogate's fit from four more seeds, each through the seven cases (~6 min;
#                         the training paths come from build/jfo_surrogate_paths when the stage ran here):
#                         reports/jfo_surrogate_seeds.json
#   train-time-ranking    the training-time study at twice the subsample (24 seeds): the same ranking?
#                         (~3 min after the stage, whose seeds it takes from cache/train_time):
#                         reports/train_time_ranking.json
#   paper-scale-ablation  the paper's split network at 40 k samples, one ingredient changed at a time (~5 min):
#                         reports/paper_scale_ablation.json
.PHONY: universal-train jfo-surrogate-seeds train-time-ranking paper-scale-ablation variants
variants: universal-train jfo-surrogate-seeds train-time-ranking paper-scale-ablation

universal-train: setup
	$(PY) experiments/universal.py part=dataset
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/universal.py part=train
	$(PY) -m fluidfilm.reporting.readme

jfo-surrogate-seeds: setup
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/jfo_surrogate.py 'jfo_surrogate.other_seeds=[1,2,3,4]' \
	    jfo_surrogate.timing_repeats=0 model_dir=build/jfo_surrogate_seeds/model report_dir=build/jfo_surrogate_seeds \
	    figure_dir=build/jfo_surrogate_seeds seeds_out=reports/jfo_surrogate_seeds.json
	$(PY) -m fluidfilm.reporting.readme

train-time-ranking: setup
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/train_time.py ranking_check.enabled=true \
	    out=reports/train_time_ranking.json
	$(PY) -m fluidfilm.reporting.readme

paper-scale-ablation: setup
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/paper_scale.py 'sizes=[]' ablation.enabled=true \
	    cache_dir=cache/paper_scale_ablation out=reports/paper_scale_ablation.json \
	    figure=build/paper_scale_ablation.png
	$(PY) -m fluidfilm.reporting.readme

# the universal surrogate's shipped weights: copy the trained ones (models/universal, `make universal-train`)
# into the package, with their checksums; commit them, then `dvc repro universal_evaluate`
.PHONY: universal-weights
universal-weights: setup
	$(PY) -c "from fluidfilm.studies.universal_study import install_weights; install_weights('models/universal', 'src/fluidfilm/surrogate/universal_weights')"

# the kernels generated for a surrogate's shape are Python source that numba compiles: write the universal
# model's (one-state and batched, float64 and float32) into build/kernels/ to read them
.PHONY: kernel-source
kernel-source: setup
	$(PY) -c "from fluidfilm import paper_bearing; from fluidfilm.surrogate.kernels import write_kernel_sources; from fluidfilm.surrogate.universal import universal_bearing; print(*write_kernel_sources(universal_bearing(paper_bearing()), 'build/kernels'), sep='\n')"

.PHONY: train-time-ci
train-time-ci: setup
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/train_time.py samples_per_seed=12000 seeds_max=1000 budget_s=36000 ranking_check.enabled=false \
	    cache_dir=cache/train_time_ci out=reports/train_time_ci.json
	$(PY) -m fluidfilm.reporting.readme

# The issue's full-scale check: single vs split trained once each on the whole paper dataset, with
# mini-batch Adam under the same division and stopping rule (Levenberg-Marquardt would take hours per network).
.PHONY: train-time-full-scale
train-time-full-scale: setup
	FLUIDFILM_UPDATE_TRACKED=1 $(PY) experiments/train_time.py main_study=false full_scale.enabled=true \
	    cache_dir=cache/train_time_full_scale out=reports/train_time_full_scale.json
	$(PY) -m fluidfilm.reporting.readme

.PHONY: paper-scale-curve paper-full-scale
# both resume an interrupted run from their finished models and per-epoch LM checkpoints, committed under
# models/paper_scale_curve and models/paper_full_scale (a fresh clone continues where the last run stopped). Time budgets
# (seconds of LM per network; a network stopped by one is recorded with stop reason max_time and not counted
# as converged; rerun with a larger budget and the LM continues from its checkpoint):
#   CURVE_BUDGET_S        per size of the curve, e.g. '{640000: 1800, 2560000: 1800}' (null: to the validation rule)
#   FULL_SCALE_BUDGET_S   the full scale's single network and the split's eps < 0.7 networks (null: the rule)
#   LM_BUDGET_S           the split's eps > 0.7 network by LM;  ADAM_BUDGET_S  the same network by Adam
#   LM_DEVICE             null: J^T J in NumPy on every core; a torch device (cuda): float64 on it, equal to
#                         round-off, continuing the same checkpoints (an epoch of the full scale: ~17 s on the
#                         project's two cores)
LM_DEVICE ?= null
CURVE_BUDGET_S ?= null
# (its own figure goes to build/: reports/figures/paper_scale_curve.png is the report stage's, drawn from every
# paper_scale report, and a target outside the pipeline writes no stage's output)
paper-scale-curve: setup
	$(PY) experiments/paper_scale.py 'sizes=[160000,640000,2560000]' ablation.enabled=false \
	    'size_budget_s=$(CURVE_BUDGET_S)' protocol.device=$(LM_DEVICE) \
	    cache_dir=models/paper_scale_curve out=reports/paper_scale_curve.json \
	    figure=build/paper_scale_curve.png \
	    'include_reports=[reports/paper_scale.json,reports/paper_full_scale.json]'

FULL_SCALE_BUDGET_S ?= null
LM_BUDGET_S ?= 14400
ADAM_BUDGET_S ?= null
paper-full-scale: setup
	$(PY) experiments/paper_scale.py 'sizes=[]' ablation.enabled=false \
	    full_scale.single.enabled=true full_scale.split.enabled=true full_scale.split_adam.enabled=true \
	    'full_scale.single.network_protocol={0: {max_time_s: $(FULL_SCALE_BUDGET_S)}}' \
	    'full_scale.split.network_protocol={0: {max_time_s: $(FULL_SCALE_BUDGET_S)}, 1: {max_time_s: $(FULL_SCALE_BUDGET_S)}, 2: {max_time_s: $(LM_BUDGET_S)}}' \
	    'full_scale.split_adam.network_protocol={0: {max_time_s: $(FULL_SCALE_BUDGET_S)}, 1: {max_time_s: $(FULL_SCALE_BUDGET_S)}, 2: {name: adam, batch_size: 4096, lr: 3.0e-3, threads: 2, max_time_s: $(ADAM_BUDGET_S)}}' \
	    protocol.progress_every_s=0 protocol.device=$(LM_DEVICE) cache_dir=models/paper_full_scale \
	    out=reports/paper_full_scale.json \
	    figure=reports/figures/paper_full_scale.png \
	    'include_reports=[reports/paper_scale.json,reports/paper_scale_curve.json]'

.PHONY: ross-env ross-peer ross-adapter test-ross
$(ROSS_STAMP): $(ROSS_PINS)
	@test -n "$(ROSS_BASE_PY)" && $(ROSS_BASE_PY) -c 'import sys; sys.exit(sys.version_info < (3, 13))' || { \
	  echo "make ross-env: no Python >= 3.13 found (ROSS 3.1 needs it): install one (pyenv install 3.13) or set ROSS_BASE_PY=/path/to/python3.13; got '$(ROSS_BASE_PY)'" >&2; exit 1; }
	rm -rf $(ROSS_VENV)
	$(ROSS_BASE_PY) -m venv $(ROSS_VENV)
	$(ROSS_VENV)/bin/pip install --quiet --disable-pip-version-check -r $(ROSS_PINS)
	touch $(ROSS_STAMP)

$(ROSS_FF_STAMP): $(ROSS_STAMP) pyproject.toml
	$(ROSS_VENV)/bin/pip install --quiet --disable-pip-version-check --no-deps -e .
	touch $(ROSS_FF_STAMP)

ross-env: $(ROSS_FF_STAMP)

# the peer benchmark (reports/benchmarks/ross_peer.json), then the adapter's report (ross_adapter.json); the
# README/docs tables are rendered from both by the workspace's own environment
ross-peer: setup ross-env
	$(ROSS_VENV)/bin/python benchmarks/bench_ross_peer.py
	$(ROSS_VENV)/bin/python benchmarks/bench_ross_adapter.py
	$(PY) -m fluidfilm.reporting.readme

ross-adapter: setup ross-env
	$(ROSS_VENV)/bin/python benchmarks/bench_ross_adapter.py
	$(PY) -m fluidfilm.reporting.readme

# the adapter's tests in the ROSS environment (in .venv they are skipped: no ROSS there)
test-ross: ross-env
	$(ROSS_VENV)/bin/python -m pytest tests/interop/test_ross_adapter.py -m slow -p no:cacheprovider
