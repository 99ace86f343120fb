# Two entry points for a machine without ROS 2 (see README.md):
#   make demo   set up .venv, run the Case I scenario through the whole node graph, write
#               out/case1_ke1e4.mcap, the paper's figures and the metrics report
#   make test   set up .venv, run ruff, mypy and the whole pytest suite
# With ROS 2 Jazzy sourced, use colcon, `ros2 run` and `ros2 launch` instead (README.md).

PYTHON ?= python3
VENV ?= .venv
OUT ?= out
SCENARIO ?= case1_ke1e4
BIN := $(VENV)/bin

.PHONY: demo test setup clean

setup: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

demo: setup
	$(BIN)/uvms run config/scenarios/$(SCENARIO).yaml --output $(OUT)/$(SCENARIO).mcap
	$(BIN)/uvms plot $(OUT)/$(SCENARIO).mcap --out $(OUT)/$(SCENARIO)
	$(BIN)/uvms report $(OUT)/$(SCENARIO).mcap

test: setup
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(BIN)/pytest

clean:
	rm -rf $(VENV) $(OUT)
