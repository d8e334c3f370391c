"""Errors that carry a message meant for the user, never a traceback."""

from __future__ import annotations


class RvppError(Exception):
    """Base class for every error rvpp reports to a user."""


class CaseError(RvppError):
    """A case (units, settings or time series) breaks a rule.

    ``problems`` lists one line per broken rule, each naming the unit, the field,
    the value and the rule, e.g. ``csp "CSP1": storage.e_min_mwh_th=1200 must be <
    storage.e_max_mwh_th=1100``.
    """

    def __init__(self, problems: list[str] | str):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))

    def __str__(self) -> str:
        if len(self.problems) == 1:
            return self.problems[0]
        lines = [f"{len(self.problems)} problems in the case:"]
        lines += [f"  - {p}" for p in self.problems]
        return "\n".join(lines)


class CaseFileError(CaseError):
    """A file of a case is not what it should be: not UTF-8 text (a zip, a workbook, a PDF,
    Latin-1 or UTF-16 text), not valid YAML or CSV, too large, or a key written twice."""


class CasePathError(CaseError):
    """A path leaves the case: an absolute path, a ``..`` step or a link out of the case
    folder or the upload; or a folder on the server asked for while that is turned off."""


class UploadError(CaseError):
    """Uploaded files do not make one case: none, several, a damaged or encrypted zip."""


class UploadLimitError(UploadError):
    """An upload costs more than allowed: bytes, unzipped bytes, rows or columns of
    history, or time spent reading it (:class:`rvpp.data.files.UploadLimits`)."""


class ModelError(RvppError):
    """The optimisation could not produce a plan (infeasible, solver failure)."""


class DataImportError(RvppError):
    """A downloaded data file cannot be read or placed in time (unknown format, ambiguous hour,
    conflicting duplicate); the message names the file, the line and the rule."""


class SettlementError(RvppError):
    """Settlement settings or imbalance prices break a rule (multipliers out of range, a short
    price below the long price); the message names the field, the value and the rule."""


def require(value: object, kind: type | tuple[type, ...], what: str, hint: str = "") -> None:
    """Refuse a value of the wrong type handed to the library, by name (``rvpp.solve: case must
    be a Case (from rvpp.load_case), not dict``), before it fails somewhere deep inside."""
    if not isinstance(value, kind):
        kinds = kind if isinstance(kind, tuple) else (kind,)
        expected = " or ".join(k.__name__ for k in kinds)
        raise TypeError(f"{what} must be a {expected}{f' ({hint})' if hint else ''}, not {type(value).__name__}")
