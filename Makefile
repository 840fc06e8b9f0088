# rll-bt: the two commands of the README.  Both create .venv when it is
# missing and install the project (with its test extras) into it.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.rll-bt-installed
SEED   ?= 1

.PHONY: sim test test-fast lint install protos clean

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

sim: $(STAMP)
	$(BIN)/rll-bt sim --seed $(SEED)

# the whole suite, after the linter (what CI runs)
test: lint
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup

# the inner loop: the linter and every test not marked slow (whole games, training)
test-fast: lint
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check .

protos: $(STAMP)
	$(BIN)/python -m rll_bt.msgs.generate

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
