"""Case folders on disk: a hardened reader of ``case.yaml``, and loading and saving a case.

``case.yaml`` is read as plain data only (no tags but those of plain data, bounded size,
depth and value count, no key written twice) before the case model validates it.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path, PurePosixPath
from typing import Any

import yaml

from ..errors import CaseError, CaseFileError, CasePathError, RvppError, require
from .case import CASE_FILE, Case, in_file_order, parse_case, settings_of
from .case_messages import kind_of
from .files import MIB, decode_text, excerpt, inside_folder, read_file, relative_path
from .history import History

MAX_CASE_YAML_BYTES = MIB  # a case.yaml of 100 units is about 80 KiB
MAX_YAML_DEPTH = 32        # nesting levels (a case uses five)
MAX_YAML_VALUES = 100_000  # values once aliases are expanded (a case of 100 units holds about 10,000)
YAML_TAG = "tag:yaml.org,2002:"
# Explicit tags a case may carry: those of plain data (``name: !!str 2025``). The other standard
# tags build values a case has no use for (!!binary, !!set, !!omap, !!pairs; a date is written
# plainly, without !!timestamp) and any other tag names a constructor rvpp does not have: both are
# refused from the parser's events, before anything is built.
PLAIN_TAGS = frozenset(YAML_TAG + kind for kind in ("str", "int", "float", "bool", "null", "seq", "map"))
NON_SPECIFIC_TAG = "!"  # "! x": no tag named (PyYAML reads the value as if untagged)
# What a value of a standard tag must be, for a message when it cannot be built (``!!float abc``).
TAG_MEANS = {"int": "a whole number", "float": "a number", "bool": "true or false", "null": "an empty value",
             "timestamp": "a valid date or time (a date is written 2025-03-18)", "str": "text", "seq": "a list",
             "map": "a mapping"}
# What PyYAML's constructors raise, besides its own errors, for a value they cannot build.
CONSTRUCTION_ERRORS = (ValueError, TypeError, AttributeError, IndexError, KeyError, OverflowError, RecursionError)


def load_case(path: str | Path) -> Case:
    """Read a case folder (or its ``case.yaml``) and validate it.

    ``case.yaml`` and the history CSV named by ``history:`` must lie inside the case
    folder: an absolute path, a ``..`` step or a link out of the folder raises
    :class:`~rvpp.errors.CasePathError` before the file is opened, so a case is a
    portable folder and never reads files beside it.
    """
    require(path, (str, os.PathLike), "rvpp.load_case: path", "a case folder or its case.yaml")
    path = Path(path)
    try:
        file = path / CASE_FILE if path.is_dir() else path
        found = file.is_file()
        target = file.resolve()
        inside = target.is_relative_to(file.parent.resolve())
    except (OSError, ValueError, RuntimeError):  # no permission, a NUL in the name, a loop of links
        found = False
    if not found:
        raise CaseError(f"no {CASE_FILE} found at {excerpt(path, 200)}")
    if not inside:  # the target is never opened nor named: it may be any file of the server
        raise CasePathError(f"{excerpt(file.name)}: is a link to a file outside the case folder; copy the file "
                            "into the folder")
    data = read_case_yaml(read_file(target, file.name, max_bytes=MAX_CASE_YAML_BYTES), file.name)
    relative = history_path(data, file.name)
    history = history_of(data, lambda: History.read_csv(inside_folder(file.parent, relative, "history", file.name),
                                                        source=str(relative)))
    return parse_case(data, history)


def history_path(data: Mapping[str, Any], file: str) -> PurePosixPath:
    """The ``history:`` of a case, checked to stay inside the case folder (nothing is opened).

    Refused with every problem of the file found without the history, in file order: a
    ``units: 5`` above a missing ``history:`` is named first."""
    try:
        return relative_path(data.get("history"), "history", file)
    except CasePathError as err:
        problems: list[str] = []
        settings_of(data, problems)
        raise CasePathError(in_file_order([*problems, *err.problems], data)) from None


def history_of(data: Mapping[str, Any], read: Callable[[], History]) -> History:
    """The history ``read()`` gives for the case settings ``data``; a history refused for its problems
    is refused after every problem of the case file found without it, the case file's first (it is read
    first), in file order, so a bad cell of the history does not hide a κ of 1.5 above it."""
    try:
        return read()
    except CaseError as err:
        if type(err) is not CaseError:  # too large, or a path: the history itself was not read
            raise
        problems: list[str] = []
        settings_of(data, problems)
        if not problems:
            raise
        raise CaseError([*in_file_order(problems, data), *err.problems]) from None


def read_case_yaml(data: bytes, file: str) -> dict[str, Any]:
    """The settings in the bytes of a ``case.yaml`` named ``file`` (not yet validated).

    The file must be UTF-8 text of at most ``MAX_CASE_YAML_BYTES``, nested at most
    ``MAX_YAML_DEPTH`` levels and at most ``MAX_YAML_VALUES`` values once its aliases
    are expanded, with no tag but those of ``PLAIN_TAGS``; its top level must be a
    mapping. A value that cannot be built (``!!float abc``, ``2025-02-30``) is named by
    its line. Raises :class:`CaseFileError`.
    """
    if len(data) > MAX_CASE_YAML_BYTES:
        raise CaseFileError(f"{file}: is larger than {MAX_CASE_YAML_BYTES // 1024} KiB; a case.yaml is usually "
                            "a few KiB")
    text = decode_text(data, file)
    try:
        _check_yaml_shape(text, file)
        loader = _CaseLoader(text)
        loader.file = file
        try:
            loaded = loader.get_single_data()
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or exc
        raise CaseFileError(f"{file}: not valid YAML{where} ({excerpt(problem, 120)})") from None
    except CONSTRUCTION_ERRORS:  # not placed at a value by _CaseLoader.construct_object
        raise CaseFileError(f"{file}: not valid YAML (a value cannot be read as plain data)") from None
    if not isinstance(loaded, Mapping):
        got = "the file is empty" if loaded is None else f"it holds {kind_of(loaded)}"
        raise CaseFileError(f"{file}: the top level must be a mapping of settings (name:, markets:, units:, ...); "
                            f"{got}")
    return dict(loaded)


_YamlBase = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when available: fast and iterative


class _CaseLoader(_YamlBase):
    """PyYAML's safe loader (plain data only: no Python objects) that refuses a key written
    twice in one mapping, at every depth, instead of keeping the last value, and reports a
    value it cannot build (``!!float abc``, ``2025-02-30``) at its line, never as a traceback."""

    file = CASE_FILE

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except CONSTRUCTION_ERRORS:
            raise yaml.constructor.ConstructorError(None, None, _cannot_build(node), node.start_mark) from None

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        if not isinstance(node, yaml.MappingNode):  # "!!map 5", "!!map [1, 2]"
            raise yaml.constructor.ConstructorError(None, None, f"{_tag_name(node.tag)} must be a mapping (key: value "
                                                    f"lines), not {_node_kind(node)}", node.start_mark)
        lines: dict[Any, int] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":  # "<<: *defaults" may be overridden on purpose
                continue
            key = self.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            if not _hashable(key):
                continue  # the base class names it
            if key in lines:
                raise CaseFileError(f'{self.file}: key "{excerpt(key)}" is written twice in one mapping (lines '
                                    f"{lines[key]} and {line}); keep one")
            lines[key] = line
        return super().construct_mapping(node, deep=deep)


def _tag_name(tag: str) -> str:
    """A tag as written: ``!!float`` for the standard ones."""
    return excerpt("!!" + tag.removeprefix(YAML_TAG) if tag.startswith(YAML_TAG) else tag, 60)


def _node_kind(node: yaml.Node) -> str:
    return "a list" if isinstance(node, yaml.SequenceNode) else "a mapping" if isinstance(
        node, yaml.MappingNode) else "a single value"


def _cannot_build(node: yaml.Node) -> str:
    """Why the value at ``node`` cannot be built, e.g. ``'abc' is not a number`` (for ``!!float abc``)."""
    means = TAG_MEANS.get(node.tag.removeprefix(YAML_TAG), "plain data")
    if not isinstance(node, yaml.ScalarNode):
        return f"{_node_kind(node)} here cannot be read as {means}"
    return f"{excerpt(node.value)!r} is not {means}"


def _hashable(value: Any) -> bool:
    try:
        hash(value)
    except TypeError:
        return False
    return True


def _check_yaml_shape(text: str, file: str) -> None:
    """Refuse YAML nested too deep, too large once aliases are expanded (a "billion laughs") or
    carrying a tag other than those of plain data, from the parser's events, before any value is built."""
    total = 0
    sizes: dict[str, int] = {}
    stack: list[list] = [[None, 0]]  # [anchor, expanded values so far] of each open collection
    for event in yaml.parse(text, Loader=_YamlBase):
        tag = getattr(event, "tag", None)
        if tag not in (None, NON_SPECIFIC_TAG) and tag not in PLAIN_TAGS:
            raise CaseFileError(f"{file}: the YAML tag {_tag_name(tag)} at line {event.start_mark.line + 1}, column "
                                f"{event.start_mark.column + 1} is not allowed in a case; remove it (a case holds "
                                "text, numbers, true/false, dates, lists and mappings; put text in quotes)")
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            if len(stack) > MAX_YAML_DEPTH:
                raise CaseFileError(f"{file}: nested more than {MAX_YAML_DEPTH} levels deep (line "
                                    f"{event.start_mark.line + 1}); a case needs a few levels")
            stack.append([event.anchor, 1])
            added = 1
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            anchor, size = stack.pop()
            if anchor is not None:
                sizes[anchor] = size
            stack[-1][1] += size
            continue
        elif isinstance(event, yaml.ScalarEvent):
            if event.anchor is not None:
                sizes[event.anchor] = 1
            stack[-1][1] += 1
            added = 1
        elif isinstance(event, yaml.AliasEvent):
            if event.anchor not in sizes:
                raise CaseFileError(f"{file}: alias *{excerpt(event.anchor)} at line {event.start_mark.line + 1} "
                                    "refers to a value not defined before it (or to itself)")
            added = sizes[event.anchor]
            stack[-1][1] += added
        else:
            continue
        total += added
        if total > MAX_YAML_VALUES:
            raise CaseFileError(f"{file}: holds more than {MAX_YAML_VALUES:,} values once its aliases (*name) are "
                                "expanded; a case holds a few thousand")


def save_case(case: Case, folder: str | Path, history_file: str = "history.csv") -> Path:
    """Write ``case.yaml`` and the history CSV into ``folder``; return the folder."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = case.to_data()
    data["history"] = history_file
    data["delivery_date"] = case.delivery_date.isoformat()
    ordered = {k: data[k] for k in ("name", "description", "delivery_date", "timezone", "dt_h", "history")}
    ordered.update({k: data[k] for k in ("markets", "uncertainty", "budgets", "solver", "units")})
    if not ordered["solver"]["mip_start"]:
        del ordered["solver"]["mip_start"]  # written only when a case carries one
    else:
        ordered["solver"]["mip_start"] = list(ordered["solver"]["mip_start"])
    ordered["markets"]["hpa_tariff_eur_per_mwh"] = list(ordered["markets"]["hpa_tariff_eur_per_mwh"])
    if "intraday" in data:
        ordered["intraday"] = data["intraday"]
    if data["provenance"]:
        ordered["provenance"] = data["provenance"]
    text = yaml.safe_dump(ordered, sort_keys=False, allow_unicode=True, width=100)
    (folder / CASE_FILE).write_text(text, encoding="utf-8")
    case.history.to_csv(folder / history_file, case.timezone)
    return folder


def check_case_folder(out: Path, written: tuple[str, ...], overwrite: bool,
                      error: type[RvppError] = RvppError) -> None:
    """Refuse, with ``error``, a path ``out`` that is not a folder, a folder where one of the
    ``written`` files belongs, and (unless ``overwrite``, the command's --force) a file there
    already."""
    if out.exists() and not out.is_dir():
        raise error(f"{out} exists and is not a folder")
    for name in written:
        target = out / name
        if target.is_dir():
            raise error(f"{target} is a folder, where the case's {name} belongs; choose another folder")
        if os.path.lexists(target) and not overwrite:
            raise error(f"{out} already holds {name}; choose another folder or overwrite it (--force)")


def write_case_folder(case: Case, out: Path, history_file: str, written: tuple[str, ...], overwrite: bool,
                      check) -> None:
    """Write ``case`` into a temporary folder beside ``out``, then move its ``written`` files into
    place in that order, calling ``check(out, overwrite)`` just before (so nothing that appeared in
    ``out`` meanwhile is replaced unless ``overwrite`` allows it)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    temp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp"))
    try:
        save_case(case, temp, history_file)
        out.mkdir(exist_ok=True)
        check(out, overwrite)
        for name in written:
            os.replace(temp / name, out / name)
    finally:
        shutil.rmtree(temp, ignore_errors=True)
