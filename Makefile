# Two entry points for a machine without ROS 2 (see README.md):
#   make demo   set up .venv, run the Case I scenario through the whole node graph, write
#               out/case1_ke1e4.mcap, the paper's figures and the metrics report
#   make test   set up .venv, run ruff, mypy and the whole pytest suite; then the suite again
#               on Python 3.12 (Jazzy's) in .venv-py3.12 when such an interpreter is found
# With ROS 2 Jazzy sourced, use colcon, `ros2 run` and `ros2 launch` instead (README.md).

PYTHON ?= python3
VENV ?= .venv
PYTHON_312 ?= $(shell tools/find-python 3.12)
VENV_312 ?= .venv-py3.12
OUT ?= out
SCENARIO ?= case1_ke1e4
BIN := $(VENV)/bin

.PHONY: demo test test-py312 setup clean sweeps

#: The shipped sweeps whose maps docs/results.md and docs/hardware.md show
#: (config/sweeps/NAME.yaml).
SWEEPS ?= stiffness_model_error noise_filter current device_rates
SWEEP_WORKERS ?= 2

setup: $(VENV)/.interfaces $(VENV)/.kernels

INTERFACES := $(shell find src/uvms_msgs interfaces -type f)

# A virtualenv with genuine ROS 2 Jazzy from PyPI wheels, the project installed editable with
# its test and sweep (Ray) extras and the pins of pyproject.toml; then our interface packages built into it with Jazzy's rosidl
# generators (rebuilt when a file of theirs changes).
define make_venv
	@tools/check-platform $(1)
	$(1) -m venv $(2)
	$(2)/bin/python -m pip install --quiet --upgrade pip
	$(2)/bin/python -m pip install --quiet -e '.[test,sweep,tune]'
	touch $(2)/.installed
endef

$(VENV)/.installed: pyproject.toml
	$(call make_venv,$(PYTHON),$(VENV))

$(VENV_312)/.installed: pyproject.toml
	$(call make_venv,$(PYTHON_312),$(VENV_312))

$(VENV)/.interfaces: $(VENV)/.installed $(INTERFACES) tools/build_interfaces.py
	$(VENV)/bin/python tools/build_interfaces.py
	touch $@

$(VENV_312)/.interfaces: $(VENV_312)/.installed $(INTERFACES) tools/build_interfaces.py
	$(VENV_312)/bin/python tools/build_interfaces.py
	touch $@

# The hot path's Numba kernels compiled into their cache once, not by the first nodes to start.
KERNEL_SOURCES := $(wildcard src/uvms_model/uvms_model/*.py src/uvms_control/uvms_control/core/*.py \
	src/uvms_control/uvms_control/core/*/*.py src/uvms_control/uvms_control/kernel_cache.py \
	src/uvms_thrusters/uvms_thrusters/*.py)

$(VENV)/.kernels: $(VENV)/.installed $(KERNEL_SOURCES) tools/compile_kernels.py
	$(VENV)/bin/python tools/compile_kernels.py
	touch $@

$(VENV_312)/.kernels: $(VENV_312)/.installed $(KERNEL_SOURCES) tools/compile_kernels.py
	$(VENV_312)/bin/python tools/compile_kernels.py
	touch $@

demo: setup
	$(BIN)/uvms run config/scenarios/$(SCENARIO).yaml --output $(OUT)/$(SCENARIO).mcap
	$(BIN)/uvms plot $(OUT)/$(SCENARIO).mcap --out $(OUT)/$(SCENARIO)
	$(BIN)/uvms report $(OUT)/$(SCENARIO).mcap

# Every shipped sweep from scratch into docs/sweeps/NAME (points.csv, figures/*.png), on a
# local Ray inside the loopback-only network namespace; about 30 min on 2 cores (device_rates
# about half of it).
sweeps: setup
	for name in $(SWEEPS); do \
	  rm -rf docs/sweeps/$$name && \
	  tools/loopback-netns $(BIN)/uvms sweep config/sweeps/$$name.yaml --out docs/sweeps/$$name \
	    --workers $(SWEEP_WORKERS) || exit $$?; \
	done

# tools/run_suite.py runs each integration module (the unit tests by sub-folder, two at a
# time; the scenario tests together) in a pytest process of its own with a time limit: a test
# hung inside C (a Fast DDS livelock) ends its module with its threads' stacks, and the rest
# of the suite runs on. The unit tests run beside the others at SCHED_IDLE.
# `make test` runs the suite on Python 3.11 and, in the same run, again on Python 3.12
# (--also-python; the colcon workspace tests on 3.11 only): both interpreters' unit tests
# fill the CPU the integration modules leave.
# The run is bounded as a whole too (SUITE_LIMIT_S): past it pytest gets SIGINT, prints where
# it was and its summary, and the target fails, rather than a hang running into the CI job's
# own 90 min without a word. 80 min: both interpreters take 63-70 min on the 2-core
# development machine and took 68 min in the CI of 2026-12-07 (4063 s, within 137 s of the
# 4200 s this was), and setup and linting must fit in the 10 min left.
SUITE_LIMIT_S ?= 4800
SUITE_GUARD := timeout --signal=INT --kill-after=120 $(SUITE_LIMIT_S)

# The Python 3.12 environment, when such an interpreter is found.
SETUP_312 := $(if $(PYTHON_312),$(VENV_312)/.interfaces $(VENV_312)/.kernels)
ALSO_312 := $(if $(PYTHON_312),--also-python $(VENV_312)/bin/python)

# Both environments are set up at once (pip's downloads and unpacking, the interface builds
# and the kernel compilation of one overlap the other's), each target's output kept together.
test:
	$(MAKE) --no-print-directory -j2 --output-sync=target setup $(SETUP_312)
	tools/ensure-debian-packages tmux=tmux chrt=util-linux
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(if $(PYTHON_312),,@echo 'make test: no Python 3.12 interpreter found; the suite runs on Python 3.11 only')
	$(SUITE_GUARD) tools/loopback-netns $(BIN)/python tools/run_suite.py $(ALSO_312)

# The suite on Python 3.12 alone.
test-py312:
ifeq ($(PYTHON_312),)
	@echo 'make test-py312: no Python 3.12 interpreter found'
else
	$(MAKE) --no-print-directory $(SETUP_312)
	$(SUITE_GUARD) tools/loopback-netns $(VENV_312)/bin/python tools/run_suite.py -q -m 'not colcon'
endif

clean:
	rm -rf $(VENV) $(VENV_312) $(OUT)
