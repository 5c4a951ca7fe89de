# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test bench clean

$(BIN)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	# compat: a path entry, not an import hook, so a user's mypy finds the packages (py.typed);
	# setuptools calls the mode transitional, so without it the install goes on and says what is lost
	$(BIN)/python -m pip install --quiet -e '.[test]' --config-settings editable_mode=compat 2>/dev/null \
		|| { echo "setuptools has no compat editable mode: installing without it (mypy outside this tree will not find markerflow)"; \
		     $(BIN)/python -m pip install --quiet -e '.[test]'; }
	touch $@

demo: $(BIN)/.installed
	$(BIN)/markerflow demo

test: $(BIN)/.installed
	$(BIN)/ruff check .
	$(BIN)/mypy
	# two workers, one per core of the CI machine; a file's tests stay on one worker, so its
	# module fixtures (labeled takes, servers) are built once
	$(BIN)/python -m pytest -q -n 2 --dist loadfile

bench: $(BIN)/.installed
	$(BIN)/python bench/jiang_table1.py
	$(BIN)/python bench/markers_realtime.py

clean:
	rm -rf $(VENV) out
