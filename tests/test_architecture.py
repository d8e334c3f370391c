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
