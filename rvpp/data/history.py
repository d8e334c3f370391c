"""Hourly history of every uncertain series of a case.

The history is one table with a ``timestamp`` column (hour-beginning, ISO 8601 with
UTC offset) and one numeric column per series: ``price_da`` [EUR/MWh],
``price_sr_up`` and ``price_sr_dn`` [EUR/MW per h], and one column per unit
(availability or consumption [MW] / [MW_th]). Rows must be hourly, contiguous and
complete; every problem is reported with the column and the time it concerns.
"""

from __future__ import annotations

import csv
import datetime as dt
import hashlib
import io
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import CaseError, CaseFileError, UploadLimitError
from .files import decode_text, excerpt, excerpt_names, read_file

PRICE_COLUMNS = ("price_da", "price_sr_up", "price_sr_dn")
# No quantity of a case comes near 1e6 (a terawatt, a terawatt-hour, a million euros per
# MWh, a hundred years in hours); a larger number is a typo, and it would wreck the
# solver's numerics instead of being refused by name.
MAX_QUANTITY = 1e6
HOUR = pd.Timedelta(hours=1)


class History:
    """An immutable, validated hourly table indexed by UTC hour-beginning instants.

    Equality and hashing use a content fingerprint, so two histories with the same
    data are interchangeable as cache keys.
    """

    def __init__(self, frame: pd.DataFrame, source: str = "history"):
        self.source = source
        self._frame = _validated(frame, source)
        self._frame.flags.allows_duplicate_labels = False
        self.fingerprint = _fingerprint(self._frame)

    @classmethod
    def read_csv(cls, path: str | Path, source: str | None = None) -> "History":
        """Read a history CSV from disk (``source``: the name shown in messages)."""
        path = Path(path)
        source = source or path.name
        if not path.exists():
            raise CaseError(f'history file "{source}" does not exist')
        return cls.from_csv(read_file(path, source), source)

    @classmethod
    def from_csv(cls, data: bytes, source: str, max_rows: int | None = None,
                 max_columns: int | None = None) -> "History":
        """Parse the bytes of a history CSV (UTF-8 text).

        ``max_rows`` and ``max_columns`` bound what an upload may hold; more raises
        :class:`~rvpp.errors.UploadLimitError` before the table is built.
        """
        text = decode_text(data, source)
        if not text.strip():
            raise CaseFileError(f"{source}: is empty; a history CSV starts with a header row such as "
                                "timestamp,price_da,price_sr_up,price_sr_dn,...")
        if max_columns is not None:
            columns = text.partition("\n")[0].count(",") + 1
            if columns > max_columns:
                raise UploadLimitError(f"{source}: has {columns:,} columns; an upload may have at most "
                                       f"{max_columns:,}")
        try:  # the header as written: pandas would rename a second "WF1" to "WF1.1"
            header = next((row for row in csv.reader(io.StringIO(text)) if row), [])
        except csv.Error as exc:
            raise CaseFileError(f"{source}: cannot be read as CSV ({excerpt(str(exc).strip(), 120)})") from None
        _refuse_repeated(header, source, CaseFileError)
        try:
            frame = pd.read_csv(io.StringIO(text), nrows=None if max_rows is None else max_rows + 1)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
            raise CaseFileError(f"{source}: cannot be read as CSV ({excerpt(str(exc).strip(), 120)})") from None
        if max_rows is not None and len(frame) > max_rows:
            raise UploadLimitError(f"{source}: has more than {max_rows:,} rows; an upload may have at most "
                                   f"{max_rows:,} (about {max_rows // 8784} years of hours)")
        return cls(frame, source=source)

    def to_csv(self, path: str | Path, timezone: str) -> None:
        """Write with local ISO-8601 timestamps (UTC offset included)."""
        out = self._frame.copy()
        local = out.index.tz_convert(timezone)
        out.insert(0, "timestamp", [t.isoformat() for t in local])
        out.to_csv(path, index=False, float_format="%.6g")

    @property
    def frame(self) -> pd.DataFrame:
        """A copy of the table [UTC index; one column per series]."""
        return self._frame.copy()

    @property
    def columns(self) -> tuple[str, ...]:
        return tuple(self._frame.columns)

    @property
    def start(self) -> pd.Timestamp:
        return self._frame.index[0]

    @property
    def end(self) -> pd.Timestamp:
        """Instant just after the last hour."""
        return self._frame.index[-1] + HOUR

    def between(self, first: pd.Timestamp, last: pd.Timestamp) -> pd.DataFrame:
        """Rows with ``first <= timestamp < last`` (tz-aware instants)."""
        index = self._frame.index
        return self._frame.loc[(index >= first) & (index < last)].copy()

    def days(self, first_day: dt.date, n_days: int, timezone: str) -> pd.DataFrame:
        """Rows of ``n_days`` whole local days starting at ``first_day`` [local index]."""
        first = pd.Timestamp(first_day).tz_localize(timezone)
        last = (pd.Timestamp(first_day) + pd.Timedelta(days=n_days)).tz_localize(timezone)
        if first < self.start or last > self.end:
            raise CaseError(
                f"{self.source}: days {first.date()} to {(last - pd.Timedelta(days=1)).date()} "
                f"are not all covered (history runs from {self.start.tz_convert(timezone).date()} "
                f"to {(self.end - HOUR).tz_convert(timezone).date()})"
            )
        rows = self.between(first, last)
        rows.index = rows.index.tz_convert(timezone)
        return rows

    def local_days(self, timezone: str) -> list[dt.date]:
        """Every local day the history covers completely."""
        local = self._frame.index.tz_convert(timezone)
        counts = pd.Series(1, index=local.date).groupby(level=0).size()
        first, last = self.start.tz_convert(timezone), (self.end - HOUR).tz_convert(timezone)
        whole = [d for d in counts.index if not (d == first.date() and first.hour != 0)]
        return [d for d in whole if not (d == last.date() and last.hour != 23)]

    def with_columns(self, columns: dict[str, np.ndarray]) -> "History":
        """A new history with columns replaced or added."""
        frame = self._frame.copy()
        for name, values in columns.items():
            frame[name] = values
        return History(frame.reset_index(names="timestamp"), source=self.source)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, History) and other.fingerprint == self.fingerprint

    def __hash__(self) -> int:
        return hash(self.fingerprint)

    def __repr__(self) -> str:
        return (f"History({self.source}: {len(self._frame)} hours, {self.start} to {self.end}, "
                f"columns={list(self._frame.columns)})")

    def __reduce__(self):
        return (_restore, (self._frame, self.source, self.fingerprint))


def _restore(frame: pd.DataFrame, source: str, fingerprint: str) -> History:
    """Unpickle without validating again: the table was validated when first built."""
    history = History.__new__(History)
    history.source, history._frame, history.fingerprint = source, frame, fingerprint
    return history


def _validated(frame: pd.DataFrame, source: str) -> pd.DataFrame:
    if isinstance(frame.index, pd.DatetimeIndex) and "timestamp" not in frame.columns:
        frame = frame.reset_index(names="timestamp")
    frame = frame.set_axis([str(c) for c in frame.columns], axis="columns")
    _refuse_repeated(list(frame.columns), source, CaseError)
    if "timestamp" not in frame.columns:
        raise CaseError(f'{source}: no "timestamp" column (found {excerpt_names(frame.columns)})')
    unprintable = [_unprintable(column, source) for column in frame.columns if not column.isprintable()]
    if unprintable:
        raise CaseError(unprintable)
    if len(frame) == 0:
        raise CaseError(f"{source}: no rows")
    stamps = _parse_timestamps(frame["timestamp"], source)
    shown = _as_written(frame["timestamp"])
    data = frame.drop(columns="timestamp")
    problems = []
    numeric = {}
    for column in data.columns:
        values = pd.to_numeric(data[column], errors="coerce")
        bad_text = (values.isna() & data[column].notna()).to_numpy()
        if bad_text.any():
            i = int(np.flatnonzero(bad_text)[0])
            problems.append(f'{source}: column "{excerpt(column)}" has a non-numeric value '
                            f"'{excerpt(data[column].iloc[i])}' at {shown[i].isoformat()}")
        missing = values.isna().to_numpy() & ~bad_text
        if missing.any():
            rows = np.flatnonzero(missing)
            problems.append(f'{source}: column "{excerpt(column)}" is empty (NaN) at {shown[rows[0]].isoformat()}'
                            + (f" and {len(rows) - 1} more hours" if len(rows) > 1 else ""))
        plain = values.to_numpy(dtype=float, na_value=0.0)
        infinite = np.isinf(plain)
        if infinite.any():
            where = shown[int(np.flatnonzero(infinite)[0])].isoformat()
            problems.append(f'{source}: column "{excerpt(column)}" is infinite at {where}')
        huge = np.flatnonzero(~infinite & (np.abs(plain) > MAX_QUANTITY))
        if len(huge):
            problems.append(f'{source}: column "{excerpt(column)}" = {plain[huge[0]]:g} at '
                            f"{shown[huge[0]].isoformat()} must lie within ±{MAX_QUANTITY:g}"
                            + (f" and {len(huge) - 1} more hours" if len(huge) > 1 else ""))
        numeric[column] = values.to_numpy(dtype=float)
    problems += _timeline_problems(stamps, shown, source)
    if problems:
        raise CaseError(problems)
    out = pd.DataFrame(numeric, index=stamps.tz_convert("UTC"))
    out.index.name = "timestamp"
    return out


def _refuse_repeated(names: list[str], source: str, error: type[CaseError]) -> None:
    """A column written twice is refused rather than one of the two read without a word."""
    seen: dict[str, int] = {}
    for i, name in enumerate(names):
        if name in seen:
            raise error(f'{source}: has the column "{excerpt(name)}" twice (columns {seen[name] + 1} and {i + 1}); '
                        "keep one")
        seen[name] = i


def _unprintable(column: str, source: str) -> str:
    """The problem of a column name holding a control character (which no unit is named with,
    and which spreadsheet files cannot hold)."""
    at = next(i for i, ch in enumerate(column) if not ch.isprintable())
    return (f'{source}: column "{excerpt(column)}" holds a non-printable character (U+{ord(column[at]):04X}) at '
            f"character {at + 1}; write column names as plain text")


def _as_written(column: pd.Series) -> list[pd.Timestamp]:
    """Timestamps with the UTC offset they were written with, for messages."""
    return [pd.Timestamp(value) for value in column]


def _parse_timestamps(column: pd.Series, source: str) -> pd.DatetimeIndex:
    if isinstance(column.dtype, pd.DatetimeTZDtype):
        return pd.DatetimeIndex(column)
    text = column.astype("string")
    if text.isna().any():
        row = int(np.flatnonzero(text.isna().to_numpy())[0])
        raise CaseError(f'{source}: "timestamp" is empty in data row {row + 1}')
    naive = ~text.str.contains(r"(?:Z|[+-]\d\d:?\d\d)$", regex=True)
    if naive.any():
        raise CaseError(f"{source}: timestamp '{excerpt(text[naive].iloc[0])}' has no UTC offset "
                        "(write e.g. 2025-03-30T03:00:00+02:00 so hours are unambiguous)")
    try:
        return pd.DatetimeIndex(pd.to_datetime(text, utc=True, format="ISO8601"))
    except (ValueError, TypeError) as exc:
        raise CaseError(f"{source}: a timestamp cannot be read ({excerpt(exc, 120)})") from None


def _timeline_problems(stamps: pd.DatetimeIndex, shown: list[pd.Timestamp], source: str) -> list[str]:
    duplicated = np.flatnonzero(stamps.duplicated())
    if len(duplicated):
        return [f"{source}: timestamp {shown[duplicated[0]].isoformat()} appears more than once"]
    if not stamps.is_monotonic_increasing:
        return [f"{source}: timestamps are not in increasing order"]
    problems = []
    off_hour = np.flatnonzero((stamps.minute != 0) | (stamps.second != 0))
    if len(off_hour):
        problems.append(f"{source}: timestamp {shown[off_hour[0]].isoformat()} is not on the hour")
    steps = stamps[1:] - stamps[:-1]
    gaps = np.flatnonzero(steps != HOUR)
    if len(gaps):
        first = (shown[gaps[0]] + HOUR).isoformat()
        missing = int(sum((steps[i] // HOUR) - 1 for i in gaps))
        problems.append(f"{source}: hour {first} is missing"
                        + (f" ({missing} missing hours in all)" if missing > 1 else "")
                        + "; the history must be hourly and contiguous")
    return problems


def _fingerprint(frame: pd.DataFrame) -> str:
    digest = hashlib.sha256()
    digest.update(",".join(frame.columns).encode())
    digest.update(frame.index.asi8.tobytes())
    digest.update(np.ascontiguousarray(frame.to_numpy(dtype=float)).tobytes())
    return digest.hexdigest()[:16]
