# Two commands on a fresh machine: `make run` (dashboard) and `make test` (full suite).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-$(shell cksum requirements.txt | cut -d' ' -f1)
PORT ?= 8501

.PHONY: install axe run test bench data reproduce clean

$(STAMP): requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

install: $(STAMP)

# axe-core for the browser tests' accessibility checks (skipped without npm).
AXE := tests/node/node_modules/axe-core/axe.min.js
$(AXE): tests/node/package.json tests/node/package-lock.json
	@if command -v npm >/dev/null 2>&1; then npm ci --no-audit --no-fund --prefix tests/node; \
	else echo "npm not found: the accessibility test will be skipped"; fi

axe: $(AXE)

run: install
	$(BIN)/streamlit run app.py --server.port $(PORT) --server.headless true

test: install axe
	$(BIN)/python -m pytest -n 2

bench: install
	$(BIN)/python benchmarks/solve_times.py
	$(BIN)/python benchmarks/studies.py
	$(BIN)/python benchmarks/dashboard.py

reproduce: install
	$(BIN)/python -m rvpp study reproduce --out out/reproduce

data: install
	$(BIN)/python -m rvpp data build

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis out tests/node/node_modules
