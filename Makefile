# rll-bt: the two commands of the README.  Both create .venv when it is
# missing and install the project (with its test extras) into it.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.rll-bt-installed
SEED   ?= 1

.PHONY: sim test test-fast lint install protos clean browser

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

sim: $(STAMP)
	$(BIN)/rll-bt sim --seed $(SEED)

# the whole suite, after the linter (what CI runs); the live-view test drives Debian's chromium.
# Three workers on two cores: the games of other teams' software (league_sim) and the process games
# run on the wall clock and leave a core idle (a 2-worker run used 1.07 cores over its 17 minutes)
test: lint browser
	$(BIN)/python -m pytest -q -n 3 --dist loadgroup --durations=30

# the inner loop: the linter and every test not marked slow (whole games, training)
test-fast: lint
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m "not slow"

# headless Chromium for the browser test of the live view (tests/games/view): Debian's package,
# installed with apt-get when root and missing; anyone else is told the one command
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then \
	    apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends chromium; \
	  else \
	    echo "the browser test needs Debian's chromium; install it with:  sudo apt-get install -y chromium" >&2; \
	    exit 1; \
	  fi; }

lint: $(STAMP)
	$(BIN)/ruff check .

protos: $(STAMP)
	$(BIN)/python -m rll_bt.msgs.generate

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
