"""What pyproject.toml declares for the installed package: every third-party module rvpp imports
comes from a declared dependency, the pins of requirements.txt satisfy the declarations, and every
folder of rvpp is a package that the install picks up."""

from __future__ import annotations

import ast
import sys
import tomllib
from importlib import metadata

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from tests.factories import ROOT

PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def declared() -> dict[str, Requirement]:
    requirements = [Requirement(r) for r in PROJECT["dependencies"]]
    requirements += [Requirement(r) for group in PROJECT.get("optional-dependencies", {}).values() for r in group]
    return {canonicalize_name(r.name): r for r in requirements}


def pins() -> dict[str, str]:
    found = {}
    for line in (ROOT / "requirements.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            found[canonicalize_name(name)] = version
    return found


def third_party_imports() -> set[str]:
    """Top-level names of the absolute imports in rvpp/, standard library and rvpp left out."""
    names = set()
    for path in (ROOT / "rvpp").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names.add(node.module.split(".")[0])
    return names - set(sys.stdlib_module_names) - {"rvpp", "__future__"}


def test_every_module_rvpp_imports_comes_from_a_declared_dependency():
    providers = metadata.packages_distributions()
    modules = third_party_imports()
    assert {"pyomo", "highspy", "pandas", "dask"} <= modules  # the scan sees what rvpp is built on
    undeclared = {module: providers.get(module) for module in modules
                  if not {canonicalize_name(d) for d in providers.get(module, [])} & set(declared())}
    assert undeclared == {}


def test_the_pinned_versions_satisfy_the_declared_ones():
    pinned = pins()
    assert {name: str(r.specifier) for name, r in declared().items()
            if name not in pinned or not r.specifier.contains(pinned[name])} == {}


def test_every_folder_of_rvpp_with_modules_is_a_package():
    folders = {path.parent for path in (ROOT / "rvpp").rglob("*.py")}
    assert len(folders) > 5
    assert sorted(str(f.relative_to(ROOT)) for f in folders if not (f / "__init__.py").is_file()) == []


def test_the_rvpp_command_runs_the_command_line():
    assert PROJECT["scripts"] == {"rvpp": "rvpp.cli:main"}
    from rvpp.cli import main

    assert main(["--help"]) == 0
