# Two commands on a fresh machine: `make run` (dashboard) and `make test` (full suite).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# Everything is installed again when requirements.txt or pyproject.toml changes.
STAMP := $(VENV)/.installed-$(shell cat requirements.txt pyproject.toml | cksum | cut -d' ' -f1)
PORT ?= 8501
# `make run` is the local, single-user dashboard: it listens on this machine only and may load
# case folders from its disk. To serve others, set ADDRESS=0.0.0.0 FOLDERS=0 (docs/dashboard.md).
ADDRESS ?= 127.0.0.1
FOLDERS ?= 1

BENCH ?= full
# Days of the backtest benchmark: a year in full mode, four weeks in quick mode.
BACKTEST_DAYS_full = 365
BACKTEST_DAYS_quick = 28

.PHONY: install axe run test test-all bench bench-studies data reproduce clean

# The project itself is installed editable, with the `rvpp` command: Dask workers started from
# this venv import rvpp wherever they run (docs/backtest.md, Parallel runs).
$(STAMP): requirements.txt pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt -e .
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

install: $(STAMP)

# axe-core for the browser tests' accessibility checks: installed on every `make test`, and
# a missing npm stops the run (the accessibility test fails without axe-core, never skips).
axe:
	@command -v npm >/dev/null 2>&1 || { echo "npm not found: install node and npm (.ci/run does)" >&2; exit 1; }
	npm ci --no-audit --no-fund --prefix tests/node

run: install
	RVPP_ALLOW_SERVER_FOLDERS=$(FOLDERS) $(BIN)/python -m dashboard --server.port $(PORT) \
		--server.address $(ADDRESS) --server.headless true

# `make test` leaves out the tests marked slow (quarter-hour reference solves, end-to-end studies, the
# longer browser walks: pyproject.toml's markers); `make test-all` runs every test.
test: install axe
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -n 2 --dist loadfile -m "not slow"

test-all: install axe
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -n 2 --dist loadfile

# Solver benchmarks, JSON in benchmarks/results/; `make bench BENCH=quick` takes under ten minutes.
bench: install
	$(BIN)/python benchmarks/run.py --mode $(BENCH)
	$(BIN)/python benchmarks/history.py
	$(BIN)/python benchmarks/backtest.py --days $(BACKTEST_DAYS_$(BENCH))
	$(BIN)/python benchmarks/dashboard.py

bench-studies: install
	$(BIN)/python benchmarks/studies.py

# The paper's studies, then the rolling backtest and recommended Γ. With the real Spanish files
# (RVPP_SPAIN_DATA, or shared/data/spain beside the project) the backtest runs on cases built from
# them. REAL_SPAN=year (the default) builds 2017-2018 twice, on the real sky and on the modelled one
# (--sky modelled --demands modelled), backtests every day of 2018 on both and recommends Γ on
# January-June, tested on July-December: hours of CPU, resumed where it stopped when run again.
# REAL_SPAN=quarter, the short version, builds November 2017-March 2018 on the real sky only, trains
# on January-February and tests on March 2018. Without the files: the synthetic case (April/May
# 2025). RVPP_BACKTEST_CASE=<case folder> chooses the case instead. WORKERS=N caps the processes.
SPAIN_DATA ?= $(if $(RVPP_SPAIN_DATA),$(RVPP_SPAIN_DATA),../shared/data/spain)
REAL_SPAN ?= year
SPAIN_FILE = $(SPAIN_DATA)/entsoe_spain_2015_2018.csv
BUILD_SPAIN = $(BIN)/python -m rvpp data build-case --from "$(SPAIN_FILE)" --fill-gaps 3 --force
reproduce: install
	@case_dir="$$RVPP_BACKTEST_CASE"; modelled=""; periods=""; \
	if [ -z "$$case_dir" ] && [ -f "$(SPAIN_FILE)" ]; then \
		if [ "$(REAL_SPAN)" = year ]; then \
			case_dir=out/spain-2017-2018; modelled=out/spain-2017-2018-modelled-sky; \
			periods="--backtest-train 2018-01-01:2018-06-30 --backtest-test 2018-07-01:2018-12-31"; \
			$(BUILD_SPAIN) --out "$$case_dir" --start 2017-01-01 --end 2018-12-31 || exit 1; \
			$(BUILD_SPAIN) --out "$$modelled" --start 2017-01-01 --end 2018-12-31 \
				--sky modelled --demands modelled || exit 1; \
		elif [ "$(REAL_SPAN)" = quarter ]; then \
			case_dir=out/spain-2018; \
			$(BUILD_SPAIN) --out "$$case_dir" --start 2017-11-01 --end 2018-03-31 || exit 1; \
		else \
			echo "REAL_SPAN=$(REAL_SPAN): choose year (2018 on both skies) or quarter (January-March 2018)" >&2; \
			exit 1; \
		fi; \
	fi; \
	RVPP_BACKTEST_CASE="$$case_dir" RVPP_BACKTEST_MODELLED_CASE="$$modelled" $(BIN)/python -m rvpp study reproduce \
		--out out/reproduce $$periods $(if $(WORKERS),--workers $(WORKERS))

data: install
	$(BIN)/python -m rvpp data build

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis out tests/node/node_modules
