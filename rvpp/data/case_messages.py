"""Messages of the case model: each problem named in the words of ``case.yaml``.

Pydantic's validation errors become one line each, located as in the file
(``csp "CSP1": storage.e_min_mwh_th=1200 must be < ...``), and raw values are shown
short and without control characters.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ValidationError

from .files import excerpt


def validate_into(model: type[BaseModel], raw: Any, label: str, problems: list[str]) -> Any:
    try:
        return model.model_validate(raw)
    except ValidationError as err:
        problems.extend(describe_errors(err, label))
        return None


def describe_errors(err: ValidationError, label: str) -> list[str]:
    """One line per error of ``err``, located as in ``case.yaml``: ``label: field.sub=value rule``.

    ``label`` names the section or unit (``markets``, ``csp "CSP1"``); empty for the top
    level. Lists are located by what their items mean (``breakpoints point 2 input``),
    never by an internal index.
    """
    prefix = f"{label}: " if label else ""
    lines = []
    for e in err.errors():
        where = _where(e["loc"])
        kind, ctx = e["type"], e.get("ctx") or {}
        if kind == "value_error":
            for line in str(ctx.get("error", e["msg"])).splitlines():
                shown = line if not where or line.startswith(where.split(" ")[0]) else f"{where}: {line}"
                lines.append(line if not label and not where else prefix + shown)
        elif kind == "missing":
            lines.append(f"{prefix}{where} is required")
        elif kind == "extra_forbidden":
            lines.append(f'{prefix}unknown field "{excerpt(where)}"')
        elif not where:
            lines.append(f"{prefix}{_rule(kind, ctx, e['msg'])}; got {kind_of(e.get('input'))}")
        else:
            lines.append(f"{prefix}{where}={show_value(e.get('input'))} {_rule(kind, ctx, e['msg'])}")
    return list(dict.fromkeys(lines))


def _where(loc: tuple) -> str:
    """A pydantic location as written in ``case.yaml``: ``storage.e_min_mwh_th``,
    ``power_block.breakpoints point 2 efficiency``, ``hpa_tariff_eur_per_mwh hour 07:00``."""
    text = ""
    for i, part in enumerate(loc):
        if isinstance(part, int):
            parent = loc[i - 1] if i else None
            if parent == "breakpoints":
                text += f" point {part + 1}"
            elif parent == "hpa_tariff_eur_per_mwh":
                text += f" hour {part:02d}:00"
            elif isinstance(parent, int) and loc[i - 2:i - 1] == ("breakpoints",):
                text += " input" if part == 0 else " efficiency"
            else:
                text += f" item {part + 1}"
        else:
            text += ("." if text else "") + excerpt(part)
    return text


def show_value(value: Any) -> str:
    """A value as the user wrote it, cut short."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)) and len(value) > 6:
        return f"[{len(value)} values]"
    if isinstance(value, Mapping):
        return "{...}" if value else "{}"
    return repr(excerpt(value)) if isinstance(value, str) else excerpt(value)


def _rule(kind: str, ctx: dict, msg: str) -> str:
    """The rule a pydantic error type stands for, in the words of the case format."""
    rules = {
        "greater_than_equal": lambda: f"must be >= {ctx.get('ge'):g}",
        "greater_than": lambda: f"must be > {ctx.get('gt'):g}",
        "less_than_equal": lambda: f"must be <= {ctx.get('le'):g}",
        "less_than": lambda: f"must be < {ctx.get('lt'):g}",
        "float_parsing": lambda: "must be a number",
        "float_type": lambda: "must be a number",
        "finite_number": lambda: "must be a finite number",
        "int_parsing": lambda: "must be a whole number",
        "int_from_float": lambda: "must be a whole number",
        "int_type": lambda: "must be a whole number",
        "int_parsing_size": lambda: "must be a whole number of a sensible size",
        "bool_parsing": lambda: "must be true or false",
        "bool_type": lambda: "must be true or false",
        "literal_error": lambda: f"must be {ctx.get('expected')}",
        "string_type": lambda: "must be text (put it in quotes if it looks like a number or a date)",
        "string_pattern_mismatch": lambda: "must start with a letter or digit and use at most 40 letters, "
                                            "digits, '_', '.' or '-'",
        "string_too_short": lambda: "must not be empty",
        "string_too_long": lambda: f"must have at most {ctx.get('max_length')} characters",
        "too_short": lambda: f"must have at least {ctx.get('min_length')} values (has {ctx.get('actual_length')})",
        "too_long": lambda: f"must have at most {ctx.get('max_length')} values (has {ctx.get('actual_length')})",
        "date_from_datetime_parsing": lambda: "must be a date such as 2025-03-18",
        "date_from_datetime_inexact": lambda: "must be a date such as 2025-03-18, without a time of day",
        "date_parsing": lambda: "must be a date such as 2025-03-18",
        "date_type": lambda: "must be a date such as 2025-03-18",
        "tuple_type": lambda: "must be a list",
        "list_type": lambda: "must be a list",
        "iterable_type": lambda: "must be a list",
        "model_type": lambda: "must be a mapping of fields",
        "model_attributes_type": lambda: "must be a mapping of fields",
        "dict_type": lambda: "must be a mapping",
        "mapping_type": lambda: "must be a mapping",
        "is_instance_of": lambda: f"must be {ctx.get('class', 'of another type')}",
        "recursion_loop": lambda: "is nested too deep",
    }
    return rules.get(kind, lambda: msg[:1].lower() + msg[1:])()


def as_number(value: Any, whole: bool = False) -> float | int | str:
    """``value`` as a finite number (an ``int`` with ``whole``), or the rule it breaks.

    Numbers written as text (``"70"``) count, as they do for every other field.
    """
    wanted = "must be a whole number" if whole else "must be a number"
    if isinstance(value, bool):
        return wanted
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            return wanted
    if isinstance(value, int):
        if whole:
            return value
        try:
            return float(value)
        except OverflowError:
            return "must be a finite number"
    if not isinstance(value, float):
        return wanted
    if not math.isfinite(value):
        return "must be a finite number"
    if whole:
        return int(value) if value.is_integer() else wanted
    return value


def kind_of(value: Any) -> str:
    """What a YAML value is, in the words of the format: a list, a mapping, text, a number."""
    if value is None:
        return "nothing (an empty value)"
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "text"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, Mapping):
        return "a mapping"
    return "a " + type(value).__name__
