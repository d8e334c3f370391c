"""Plain encodings of what the store keeps: JSON-safe data, a case's settings, a history table."""

from __future__ import annotations

import io
import json
from typing import Any

import pandas as pd

from ..data.case import Case
from ..data.history import History


def jsonable(value: Any) -> Any:
    """``value`` as plain JSON data (dates, enums and paths become their text)."""
    return json.loads(json.dumps(value, default=str))


def case_data(case: Case) -> dict[str, Any]:
    """The case in the layout of ``case.yaml``, without its history, as JSON data."""
    return jsonable(case.to_data())


def history_bytes(history: History) -> bytes:
    """The history table as Parquet (UTC index, one column per series)."""
    buffer = io.BytesIO()
    history.frame.to_parquet(buffer, index=True)
    return buffer.getvalue()


def history_from(data: bytes, source: str) -> History:
    """A :class:`History` from :func:`history_bytes`, validated again."""
    frame = pd.read_parquet(io.BytesIO(data))
    return History(frame.reset_index(names="timestamp"), source=source)
