# actorbt: two commands do all the set-up on a fresh machine.
#   make demo   the main job (headless mission demo)
#   make test   the whole test suite
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# The real robot's ROS message packages that have no pip wheel (tf2_msgs, control_msgs,
# nav2_msgs) are built from interfaces/upstream, a separate distribution with its own stamp:
# a change to pyproject.toml does not rebuild them (about 3 minutes). See interfaces/README.md.
MSGS_STAMP := $(VENV)/.upstream-msgs
MSGS_SRC   := $(addprefix interfaces/upstream/,pyproject.toml CMakeLists.txt) \
  $(wildcard $(addprefix interfaces/upstream/*/,CMakeLists.txt package.xml msg/*.msg srv/*.srv action/*.action))
# actorbt's own action types (actorbt_interfaces): a distribution of its own too, so that
# actorbt is pure Python and the engine installs without ROS (docs/install.md).
IFACE_STAMP := $(VENV)/.actorbt-interfaces
IFACE_SRC   := $(addprefix interfaces/,pyproject.toml CMakeLists.txt package.xml) \
  $(wildcard interfaces/action/*.action interfaces/srv/*.srv)
# Debian packages: cmake/g++ build the ROS action types, EGL renders the camera headless,
# graphviz draws trees.
DEBS   := cmake g++ libegl1 libegl-mesa0 graphviz

export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST

.PHONY: test demo bench deps venv clean

deps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	fi

define venv_ready
	@$(MAKE) --no-print-directory deps
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
endef

$(MSGS_STAMP): $(MSGS_SRC)
	$(venv_ready)
	$(PY) -m pip install -q ./interfaces/upstream
	@touch $(MSGS_STAMP)

$(IFACE_STAMP): $(IFACE_SRC) | $(MSGS_STAMP)
	$(venv_ready)
	$(PY) -m pip install -q ./interfaces
	@touch $(IFACE_STAMP)

# Order-only on the message packages: they are built first, but rebuilding them does not
# reinstall actorbt.
$(STAMP): pyproject.toml | $(IFACE_STAMP)
	$(venv_ready)
	$(PY) -m pip install -q -e ".[test]"
	@touch $(STAMP)

venv: $(STAMP)

# the linter, the format check and the type check first (seconds), then the suite
# on one worker more than the cores (pytest-xdist; tests/conftest.py says why). A test file
# stays in one worker (--dist loadgroup would not: with pytest 9 xdist 3.8's group marks no
# longer reach the scheduler, and every test is sent alone), except the runs of minutes,
# which go first, each alone (--no-loadscope-reorder keeps that order). The slowest tests
# are listed at the end.
test: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m mypy
	$(PY) -m pytest -q -n auto --dist loadfile --no-loadscope-reorder --durations=25

demo: $(STAMP)
	$(VENV)/bin/actorbt demo

bench: $(STAMP)
	$(PY) bench/run_all.py

clean:
	rm -rf $(VENV) build
