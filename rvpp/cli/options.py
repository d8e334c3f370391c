"""The command line's shared options: argparse types that refuse a bad value in the option's
words, the parser with one-line errors, and the options the study and backtest commands share."""

from __future__ import annotations

import argparse
import datetime as dt
import math
import re
from dataclasses import dataclass
from pathlib import Path

from ..backtest.settings import parse_period
from ..data.case import FIRST_DATE, ISO_DATE, LAST_DATE, MAX_QUANTITY
from ..data.files import excerpt
from ..data.variants import parse_markets
from ..errors import RvppError
from ..settle.penalties import Penalties
from ..solving.parallel import SCHEDULERS

DEFAULT_CASE = Path(__file__).resolve().parents[2] / "data" / "cases" / "paper"
FAILURE = 1
INTERRUPTED = 130  # the shell's code for a command ended by Ctrl-C


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``error: --gap: ...``) and exit code 1."""

    def error(self, message: str) -> None:
        message = re.sub(r"^argument ([^:]+): ", r"\1: ", message)
        self.exit(FAILURE, f"error: {message} (see {self.prog} --help)\n")


@dataclass(frozen=True)
class Number:
    """An option's value: a finite number within bounds (``whole``: an integer), as an argparse ``type``.

    Anything else raises :class:`argparse.ArgumentTypeError` naming the value and the
    allowed range, e.g. ``'nan' is not allowed; give a number > 0 [s]``.
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    whole: bool = False
    unit: str = ""

    def __call__(self, text: str) -> float | int:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not a number; give {self.rule}") from None
        if not math.isfinite(value) or (self.whole and not value.is_integer()) or not self._within(value):
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not allowed; give {self.rule}")
        return int(value) if self.whole else value

    def _within(self, value: float) -> bool:
        above = self.low is None or (value > self.low if self.low_open else value >= self.low)
        below = self.high is None or (value < self.high if self.high_open else value <= self.high)
        return above and below

    @property
    def rule(self) -> str:
        kind = "a whole number" if self.whole else "a number"
        unit = f" [{self.unit}]" if self.unit else ""
        if self.low is not None and self.high is not None:
            return (f"{kind} in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                    f"{')' if self.high_open else ']'}{unit}")
        if self.low is not None:
            return f"{kind} {'>' if self.low_open else '>='} {self.low:g}{unit}"
        return f"a finite {kind[2:]}{unit}"


def choice_of(values: tuple[float, ...], unit: str):
    """An argparse ``type`` accepting one of ``values`` (numbers), e.g. the period lengths."""
    allowed = ", ".join(f"{v:g}" for v in values)

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if value not in values:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not allowed; give one of {allowed} [{unit}]")
        return value
    return convert


def listed(convert, what: str):
    """An argparse ``type`` for a comma-separated list: every item given, none empty, each through
    ``convert`` (which may raise ``argparse.ArgumentTypeError`` or ``ValueError``)."""
    def parse(text: str) -> tuple:
        items = [part.strip() for part in text.split(",")]
        if not text.strip():
            raise argparse.ArgumentTypeError(f"is empty; give {what}")
        empty = [i for i, item in enumerate(items, start=1) if not item]
        if empty:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r}: item {empty[0]} is empty; give {what}")
        try:
            return tuple(convert(item) for item in items)
        except (argparse.ArgumentTypeError, ValueError, RvppError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return parse


def market_list(text: str) -> str:
    """``--markets``: a comma-separated subset of DAM,SRM,HPA including DAM, checked now."""
    try:
        parse_markets(text)
    except RvppError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def date_option(text: str) -> str:
    """An argparse ``type`` for a delivery date: ``YYYY-MM-DD``, a day of the calendar, within the
    dates rvpp plans; refused in the option's words (``--date: '2025-02-30' is not a day ...``)."""
    try:
        day = dt.date.fromisoformat(text) if ISO_DATE.fullmatch(text) else None
    except ValueError:
        day = None
    if day is None:
        raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not a day of the calendar; give YYYY-MM-DD, "
                                         "e.g. 2025-03-18")
    if not FIRST_DATE <= day <= LAST_DATE:
        raise argparse.ArgumentTypeError(f"{text} is not allowed; give a day from {FIRST_DATE} to {LAST_DATE}")
    return text


def path_option(text: str) -> Path:
    """An argparse ``type`` for a file or folder: an empty value is refused, not read as "."."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty; give a file or folder")
    return Path(text)


def add_settlement_options(parser: argparse.ArgumentParser) -> None:
    """The options of the settlement of realized days: penalty multipliers, the price of
    unserved heat and the turbine schedule (shared by the studies and the backtest)."""
    penalties = Penalties()
    multiplier = Number(0, MAX_QUANTITY)
    parser.add_argument("--m-def", type=multiplier, default=penalties.m_def,
                        help=f"deficit price multiplier, 0 to {MAX_QUANTITY:g} (default {penalties.m_def:g})")
    parser.add_argument("--m-sur", type=multiplier, default=penalties.m_sur,
                        help=f"surplus price multiplier, 0 to {MAX_QUANTITY:g} (default {penalties.m_sur:g})")
    parser.add_argument("--m-sr", type=multiplier, default=penalties.m_sr,
                        help=f"reserve shortfall price multiplier, 0 to {MAX_QUANTITY:g} (default {penalties.m_sr:g})")
    parser.add_argument("--c-heat", type=Number(0, MAX_QUANTITY, unit="EUR/MWh_th"), metavar="EUR_PER_MWH",
                        help="price of unserved heat (default: twice the highest HPA tariff)")
    parser.add_argument("--fix-commitment", action="store_true",
                        help="settle with the plan's CSP turbine schedule: no start where the plan is off")

def choice(allowed: tuple[str, ...]):
    def convert(name: str) -> str:
        if name not in allowed:
            raise argparse.ArgumentTypeError(f"unknown {excerpt(name)!r}; choose from {', '.join(allowed)}")
        return name
    return convert


def market_set(text: str) -> str:
    parse_markets(text)  # raises a CaseError naming the market
    return text


def scheduler_option(text: str) -> str:
    """``--scheduler``: a name of :data:`SCHEDULERS` or a Dask scheduler address ``[proto://]host:port``."""
    if text in SCHEDULERS or re.fullmatch(r"(?:[a-z]+://)?[^\s:/]+:\d{1,5}", text):
        return text
    raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is neither {', '.join(SCHEDULERS)} nor a scheduler "
                                     "address such as tcp://10.0.0.5:8786")


def period_option(text: str):
    """``--backtest-train`` / ``--backtest-test``: ``FIRST:LAST`` as two dates."""
    try:
        return parse_period(text, "period")
    except RvppError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
