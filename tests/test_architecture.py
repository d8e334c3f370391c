"""The package's structure (docs/architecture.md): layers that only import downward, no cycles
between sub-packages, function-local imports only where they keep a heavy dependency out of a
command that does not need it, and a narrow face for the dashboard."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "rvpp"


def _function_local_imports(path: Path) -> list[tuple[int, str]]:
    """(line, source line) of every import statement inside a function of ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    lines = path.read_text(encoding="utf-8").splitlines()
    found = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for inner in ast.walk(node):
                if isinstance(inner, (ast.Import, ast.ImportFrom)):
                    found.append((inner.lineno, lines[inner.lineno - 1]))
    return found


def test_the_import_contracts_hold():
    """lint-imports reads the contracts of pyproject.toml: the layers and no cycles between sub-packages."""
    run = subprocess.run([sys.executable, "-c", "import sys; from importlinter.cli import lint_imports; "
                          "sys.exit(lint_imports(no_cache=True, no_logo=True))"], cwd=ROOT, capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "2 kept, 0 broken" in run.stdout


def test_a_function_local_import_says_why():
    """A function-local import is allowed only to keep a heavy dependency out of a path that does not
    need it, with a comment on its line or the line before saying so."""
    unexplained = []
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").splitlines()
        for lineno, line in _function_local_imports(path):
            first = lineno - 1  # the comment may head the block of imports this one belongs to
            while first > 0 and lines[first - 1].strip().startswith(("from ", "import ", "#")):
                first -= 1
            context = " ".join(lines[first:lineno])
            if "heavy" not in context:
                unexplained.append(f"{path.relative_to(ROOT)}:{lineno}: {line.strip()}")
    assert not unexplained, "function-local imports without a 'heavy' comment:\n" + "\n".join(unexplained)


def test_the_checker_finds_a_function_local_import(tmp_path):
    """The scan above sees imports nested in functions (a check that cannot fail would prove nothing)."""
    sample = tmp_path / "sample.py"
    sample.write_text("import os\n\n\ndef f():\n    from json import dumps\n    return dumps\n", encoding="utf-8")
    assert _function_local_imports(sample) == [(5, "    from json import dumps")]


def _dashboard_imports() -> dict[str, set[str]]:
    """Every module the pages, ``dashboard/`` and ``app.py`` import, with the files importing it."""
    found: dict[str, set[str]] = {}
    files = [*sorted((ROOT / "pages").glob("*.py")), *sorted((ROOT / "dashboard").glob("*.py")), ROOT / "app.py"]
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            else:
                continue
            for name in names:
                found.setdefault(name, set()).add(path.name)
    return found


def test_the_dashboard_reaches_rvpp_through_its_face():
    """Pages and dashboard/ import rvpp's public names and rvpp.service (docs/architecture.md), at most 12
    distinct rvpp modules, and never the store's database library."""
    imports = _dashboard_imports()
    rvpp_modules = {name for name in imports if name == "rvpp" or name.startswith("rvpp.")}
    assert len(rvpp_modules) <= 12, sorted(rvpp_modules)
    assert rvpp_modules <= {"rvpp", "rvpp.service"}, sorted(rvpp_modules - {"rvpp", "rvpp.service"})
    assert not {name for name in imports if name.split(".")[0] == "sqlalchemy"}


def test_every_service_name_resolves():
    """Each name rvpp.service offers loads (a mistyped location would fail only when a page first used it)."""
    import rvpp.service as service

    assert set(service.__all__) == set(service._WHERE)
    for name in service.__all__:
        assert getattr(service, name) is not None, name
