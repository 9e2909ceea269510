# pinbore: `make` sets up .venv and runs the default scenes through to the report;
# `make test` runs the test suite. `make help` lists every target.

SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
PINBORE := $(VENV)/bin/pinbore
STAMP := $(VENV)/.installed
NP ?= 1
# parallel jobs by default, one per core (JOBS=1 for one job at a time, in order)
JOBS ?= $(shell nproc 2>/dev/null || echo 1)
MAKEFLAGS += --jobs=$(JOBS)
.DEFAULT_GOAL := all

# Python 3.12 (DOLFINx wheels need >= 3.12): the first candidate that runs and is 3.12
# (a pyenv shim on PATH may not run), from PATH, then the pyenv installs, newest first.
PYTHON312 ?= $(shell for p in $$(command -v python3.12) \
                 $$(ls -d $(HOME)/.pyenv/versions/3.12.*/bin/python3.12 2>/dev/null | sort -rV) \
                 /usr/local/bin/python3.12 /usr/bin/python3.12; do \
               "$$p" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 12))' 2>/dev/null \
               && { echo "$$p"; break; }; done)

FEM_SCENES := $(basename $(notdir $(wildcard scenes/fem/*.toml)))
FEM_CURVES := $(FEM_SCENES:%=build/fem/%/curve.csv)
MESHES := $(FEM_SCENES:%=build/mesh/%/mesh.msh)
IMPACT_SCENES := $(basename $(notdir $(wildcard scenes/impact/*.toml)))
IMPACT_RUNS := $(IMPACT_SCENES:%=build/impact/%/impact.json)
MODES_SCENES := $(basename $(notdir $(wildcard scenes/modes/*.toml)))
MODES_RUNS := $(MODES_SCENES:%=build/modes/%/body.npz)
REDUCED_SCENES := $(basename $(notdir $(wildcard scenes/reduced/*.toml)))
REDUCED_RUNS := $(REDUCED_SCENES:%=build/reduced/%/summary.json)
MPIEXEC := $(if $(filter-out 1,$(NP)),$(VENV)/bin/mpiexec -n $(NP))
DYNAMICS_SCENE := scenes/reduced/slider_crank_flores2004.toml
SPATIAL_DYNAMICS_SCENE := scenes/reduced/spatial_slider_crank_flores_misaligned.toml
CONTINUATION_SCENE := scenes/reduced/impact_oscillator.toml
DYNAMICS := $(addprefix build/dynamics/,poincare/summary.json bifurcation/summary.json design/summary.json \
                                        spatial_poincare/summary.json spatial_bifurcation/summary.json \
                                        continuation/summary.json)
STUDY_RUNS := $(patsubst studies/%.toml,build/study/%/summary.json,$(wildcard studies/*.toml))
WEAR_SCENES := $(basename $(notdir $(wildcard scenes/wear/*.toml)))
WEAR_RUNS := $(WEAR_SCENES:%=build/wear/%/summary.json)
# the studies whose points' curves and impacts the calibration reads
CALIBRATION_STUDIES := $(addprefix build/study/,$(addsuffix /summary.json,calibration_2d calibration_3d restitution))

# The code each command runs, read from the code: build/deps.mk (written by core/codedeps.py,
# plain Python, so before .venv exists; again whenever a source file changes) sets
# CODE_<command>, the source files of the import closure of the command's stage (its scene
# model and runner in the registry pinbore/stages.py, lazy imports included), and
# LAWS_SCENES, the mechanism scenes whose TOML names a laws_file. Read by every goal but
# clean and help (the rules below need it).
DEPS_PYTHON = $(if $(wildcard $(PY)),$(PY),$(or $(PYTHON312),python3))
ifneq ($(if $(MAKECMDGOALS),$(filter-out clean help,$(MAKECMDGOALS)),all),)
include build/deps.mk
endif
# (+: written under make -n too, whose dry run needs the rules it sets)
build/deps.mk: core/codedeps.py pyproject.toml $(wildcard scenes/reduced/*.toml)
	+@mkdir -p $(@D) && { $(DEPS_PYTHON) -I core/codedeps.py . > $@.tmp && mv $@.tmp $@; } || { rm -f $@.tmp; exit 1; }

DYNAMICS_CODE := $(CODE_dynamics) $(STAMP)
# the multibody engine is the compiled core's (built by make venv): every run may start at
# once; only the runs whose scene reads the laws file wait for the calibration
LAWS_RUNS := $(LAWS_SCENES:%=build/reduced/%/summary.json)
DYNAMICS_DEPS := $(DYNAMICS_SCENE) $(DYNAMICS_CODE)
SPATIAL_DYNAMICS_DEPS := $(SPATIAL_DYNAMICS_SCENE) $(DYNAMICS_CODE)

.PHONY: all venv mesh fem impact modes calibration reduced dynamics study wear report bench stress test test-slow docs clean help
.DELETE_ON_ERROR:

all: report ## set up .venv, run the default scenes, build the report (the main job)

help: ## list the targets
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  make %-10s %s\n", $$1, $$2}'
	@echo "  variables: NP=N runs FE scenes on N MPI ranks (make fem NP=2); JOBS=N jobs at once (default: the cores)"

venv: $(STAMP) ## create .venv with Python 3.12 and the pinned dependencies

# the packages of the source: the editable install maps each module where it was when
# installed, so a package added or moved (a module become a package) installs again, without
# making the results older (an order-only prerequisite of the stamp; before .venv exists there
# is nothing to install again)
LAYOUT := $(VENV)/.layout
$(LAYOUT): $(wildcard */__init__.py */*/__init__.py */*/*/__init__.py)
	@mkdir -p $(VENV)
	@if [ -x $(PY) ] && [ -e $(STAMP) ]; then $(VENV)/bin/pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .; fi
	@touch $@

# the compiled core (cpp/) builds in the editable install; a change of it rebuilds it
$(STAMP): requirements.lock pyproject.toml CMakeLists.txt $(wildcard cpp/*.cpp cpp/*.h cpp/*/*.cpp cpp/*/*.h) | $(LAYOUT)
	@test -n "$(PYTHON312)" || { echo "make: Python 3.12 not found (PATH or ~/.pyenv/versions/3.12.*); set PYTHON312=/path/to/python3.12" >&2; exit 2; }
	$(PYTHON312) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r requirements.lock
	$(VENV)/bin/pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
	touch $@

mesh: $(MESHES) ## build the meshes of the showcase FE scenes (build/mesh/<scene>/)

build/mesh/%/mesh.msh: scenes/fem/%.toml $(CODE_mesh) $(STAMP)
	$(PINBORE) mesh $< --out build/mesh/$*

fem: $(FEM_CURVES) ## solve the default FE scenes (build/fem/<scene>/)

build/fem/%/curve.csv: scenes/fem/%.toml $(CODE_fem) $(STAMP)
	$(MPIEXEC) $(PINBORE) fem $< --out build/fem/$*

# the worn joint's FE (its wear_file, written by the wear run)
build/fem/flores_worn/curve.csv build/mesh/flores_worn/mesh.msh: build/wear/slider_crank_flores2004/summary.json

impact: $(IMPACT_RUNS) ## run the dynamic impacts of scenes/impact/ (build/impact/<scene>/)

build/impact/%/impact.json: scenes/impact/%.toml $(CODE_impact) $(STAMP)
	$(PINBORE) impact $< --out build/impact/$*

modes: $(MODES_RUNS) ## reduce the flexible bodies of scenes/modes/ to their modes (build/modes/<scene>/)

build/modes/%/body.npz: scenes/modes/%.toml $(CODE_modes) $(STAMP)
	$(PINBORE) modes $< --out build/modes/$*

calibration: build/calibration/laws.json ## fit and rank the contact laws on the calibration studies' curves (2D and 3D), the restitution on their impacts

build/calibration/laws.json: $(CALIBRATION_STUDIES) $(CODE_calibrate) $(STAMP)
	$(PINBORE) calibrate build/study/calibration_2d/points/*/curve.csv build/study/calibration_3d/points/*/curve.csv \
	    --impacts build/study/restitution/points/*/impact.json --out build/calibration

# the calibration studies: FE and impact points (their curves, impact.json and history.csv
# kept under build/study/<study>/points/<point>/)
$(CALIBRATION_STUDIES): build/study/%/summary.json: studies/%.toml studies/bases/%.toml $(CODE_study) $(STAMP)
	$(PINBORE) study $< --out build/study/$* --cache build/study/cache

reduced: $(REDUCED_RUNS) ## run the mechanisms with clearance joints (build/reduced/<scene>/)

$(LAWS_RUNS): build/calibration/laws.json
build/reduced/%/summary.json: scenes/reduced/%.toml $(MODES_RUNS) $(CODE_reduced) $(STAMP)
	$(PINBORE) reduced $< --out build/reduced/$*

dynamics: $(DYNAMICS) ## Poincare maps, bifurcation diagrams and design map of the slider-crank (planar, misaligned spatial); the impact oscillator's continued frequency response (build/dynamics/)

study: $(STUDY_RUNS) ## the studies of studies/: the calibration curves and impacts, Monte Carlo of the Flores slider-crank (exceedance, tolerance band), Sobol indices of the solar-panel deployment (build/study/)

# (a wear study's points read their joint's FE run)
build/study/wear_coefficient/summary.json: build/fem/flores_wear/curve.csv $(wildcard scenes/wear/*.toml)

# (a mechanism study's points run on the local cores)
build/study/%/summary.json: studies/%.toml $(wildcard scenes/reduced/*.toml) $(CODE_study) $(STAMP)
	$(PINBORE) study $< --out build/study/$* --cache build/study/cache

# (the sweeps run their points on the local cores; their per-point caches make a rerun resume)
build/dynamics/poincare/summary.json: $(DYNAMICS_DEPS)
	$(PINBORE) dynamics $< --analysis poincare --transient 50 --periods 100 --out build/dynamics/poincare

build/dynamics/bifurcation/summary.json: $(DYNAMICS_DEPS)
	$(PINBORE) dynamics $< --analysis bifurcation --parameter clearance --range 1e-4 5e-4 \
	    --points 40 --transient 30 --periods 30 --out build/dynamics/bifurcation \
	    --cache build/dynamics/cache

build/dynamics/design/summary.json: $(DYNAMICS_DEPS)
	$(PINBORE) dynamics $< --analysis design --range 1e-4 5e-4 --points 5 --speeds 2000 5000 4 \
	    --transient 10 --periods 10 --max-force 20000 --max-deviation 1.0 \
	    --out build/dynamics/design --cache build/dynamics/cache

build/dynamics/spatial_poincare/summary.json: $(SPATIAL_DYNAMICS_DEPS)
	$(PINBORE) dynamics $< --analysis poincare --transient 20 --periods 40 --out build/dynamics/spatial_poincare

# (the clearance stays above 0.175 mm, below which the tilted journal does not fit its bore)
build/dynamics/spatial_bifurcation/summary.json: $(SPATIAL_DYNAMICS_DEPS)
	$(PINBORE) dynamics $< --analysis bifurcation --parameter clearance --range 2e-4 5e-4 \
	    --points 20 --transient 10 --periods 20 --out build/dynamics/spatial_bifurcation \
	    --cache build/dynamics/cache

# the frequency response of the impact oscillator: its periodic motions continued through
# grazing and its bifurcations, beside direct up- and down-sweeps (the hysteresis)
build/dynamics/continuation/summary.json: $(CONTINUATION_SCENE) $(DYNAMICS_CODE)
	$(PINBORE) dynamics $< --analysis continuation --parameter frequency --range 10 30 --points 200 \
	    --transient 30 --sweeps 41 --periods 5 --out build/dynamics/continuation

wear: $(WEAR_RUNS) ## wear the clearance joints of scenes/wear/ by Archard's law on their FE pressure (build/wear/<scene>/)

# a wear scene's FE run (its pressure_file's)
build/wear/slider_crank_flores2004/summary.json build/wear/slider_crank_flores2004_coupled/summary.json: build/fem/flores_wear/curve.csv
build/wear/%/summary.json: scenes/wear/%.toml $(wildcard scenes/reduced/*.toml) $(CODE_wear) $(STAMP)
	$(PINBORE) wear $< --out build/wear/$*

report: build/report/index.html ## build build/report/index.html from the results

build/report/index.html: $(FEM_CURVES) $(MESHES) $(MODES_RUNS) build/calibration/laws.json $(REDUCED_RUNS) $(DYNAMICS) $(STUDY_RUNS) $(WEAR_RUNS) \
                         $(wildcard bench/*.csv) $(CODE_report) $(STAMP)
	@# a report folder of a pinbore that wrote no output marker, holding its index.html alone
	@if [ -d build/report ] && [ ! -e build/report/.pinbore-output ] && [ "$$(ls -A build/report)" = "index.html" ]; then rm -rf build/report; fi
	$(PINBORE) report --build build --out build/report
	@echo "report: $(abspath $@)"

bench: build/study/calibration_2d/summary.json $(MODES_RUNS) build/fem/flores_wear/curve.csv build/fem/flores_worn/curve.csv $(STAMP) ## run the benchmarks: bench/*.csv and plots (a few minutes)
	$(PY) bench/fem2d.py --out bench
	$(PY) bench/fem3d.py --out bench
	$(PY) bench/plastic.py --out bench
	$(PY) bench/first_yield.py --out bench
	$(PY) bench/calibrate.py --out bench
	$(PY) bench/multibody.py --out bench
	$(PY) bench/sweep.py --out bench
	$(PY) bench/study.py --out bench
	$(PY) bench/impact.py --out bench
	$(PY) bench/newton.py --all --out bench
	$(PY) bench/discretisation.py --out bench
	$(PY) bench/modes.py --out bench
	$(PY) bench/flexible.py --out bench
	$(PY) bench/continuation.py --out bench
	$(PY) bench/wear.py --out bench
	$(PY) bench/worn_order.py --out bench
	$(PY) bench/worn_pressure.py --out bench

stress: build/fem/flores_wear/curve.csv $(STAMP) ## the stress matrix and the reliability audit: bench/stress_*.csv, bench/stress.png, bench/audit.csv (about 7 + 3 min)
	$(PY) bench/stress.py --out bench
	$(PY) bench/audit.py --out bench

test: $(STAMP) ## run the test suite (what CI runs)
	$(PY) -m pytest -n 2 -m "not slow" tests

test-slow: $(STAMP) ## run the long tests too
	$(PY) -m pytest -n 2 tests

# the scenes' JSON Schemas (docs/schemas/) rewritten where a scene model changed, then the
# site; -n: every reference must resolve; -W --keep-going: every warning shown, then a failure
docs: $(STAMP) ## build the documentation into build/docs/html (Sphinx + MyST, offline; warnings are errors)
	@for d in build/docs/doctrees build/docs/html; do if [ -e $$d ] && [ ! -d $$d ]; then \
	    echo "make docs: $$d is a file, not a folder: remove it" >&2; exit 2; fi; done
	$(PY) docs/_ext/scene_reference.py
	$(PY) -m sphinx -W --keep-going -n -q -b html -d build/docs/doctrees docs build/docs/html
	@echo "docs: $(abspath build/docs/html/index.html)"

clean: ## remove build/ (keeps .venv)
	rm -rf build
