"""Cases as files to upload or download: a zip of a case folder, a ``case.yaml`` with its
history CSV, or an Excel case workbook (:mod:`rvpp.outputs.workbook`).

:func:`read_case_files` takes the files as ``{file name: bytes}`` and returns a validated
:class:`~rvpp.data.case.Case`; anything wrong raises :class:`~rvpp.errors.CaseError` with a
message meant for the person who uploaded the files.

An upload is read in memory and never touches the server's disk: a case may only read
the files that came with it. An uploaded file or zip member whose name is absolute or
takes a ``..`` step, a link inside a zip, and a ``history:`` that leaves the upload are
refused (:class:`~rvpp.errors.CasePathError`) before anything is read. What an upload
may cost is bounded by :class:`~rvpp.data.files.UploadLimits`
(:class:`~rvpp.errors.UploadLimitError`).
"""

from __future__ import annotations

import io
import tempfile
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path, PurePosixPath

from ..data.case import Case, CASE_FILE, parse_case
from ..data.case_yaml import history_of, history_path, read_case_yaml, save_case
from ..data.files import UploadBudget, UploadLimits, excerpt, open_zip, unzip, upload_path
from ..data.history import History
from ..errors import CaseError, UploadError, UploadLimitError
from .workbook import read_case_workbook

YAML_SUFFIXES = (".yaml", ".yml")
EXPECTED = ("a zip of a case folder, a case.yaml together with its history CSV, or an Excel case "
            "workbook (.xlsx)")


def case_zip_bytes(case: Case, folder_name: str | None = None) -> bytes:
    """``case.yaml`` and ``history.csv`` of ``case`` in a zip, inside one folder named after the case
    (letters, digits, ``_ . -`` kept, anything else as ``_``: a name such as ``../x`` stays one folder)."""
    folder_name = archive_folder(folder_name or case.name)
    buffer = io.BytesIO()
    with tempfile.TemporaryDirectory() as tmp:
        folder = save_case(case, Path(tmp) / "case")
        with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(folder.iterdir()):
                archive.write(path, arcname=f"{folder_name}/{path.name}")
    return buffer.getvalue()


def archive_folder(name: str) -> str:
    """``name`` as one folder of an archive: no path separators, no leading dot, at most 80 characters."""
    safe = "".join(c if c.isascii() and (c.isalnum() or c in "_.-") else "_" for c in name).lstrip(".")[:80]
    return safe or "case"


def read_case_files(files: Mapping[str, bytes], limits: UploadLimits = UploadLimits()) -> Case:
    """A case from uploaded files (see the module docstring for the accepted forms)."""
    if not files:
        raise UploadError(f"no file given; upload {EXPECTED}")
    sent = sum(len(data) for data in files.values())
    if sent > limits.upload_bytes:
        raise UploadLimitError(f"the upload is {sent / 1024 ** 2:.1f} MiB; an upload may be at most "
                               f"{limits.upload_bytes / 1024 ** 2:g} MiB")
    budget = UploadBudget(limits)
    uploaded = {upload_path(name): data for name, data in files.items()}
    suffixes = {path: path.suffix.lower() for path in uploaded}
    zips = [p for p, s in suffixes.items() if s == ".zip"]
    workbooks = [p for p, s in suffixes.items() if s in (".xlsx", ".xlsm")]
    yamls = [p for p, s in suffixes.items() if s in YAML_SUFFIXES]
    names = ", ".join(sorted(excerpt(p, 80) for p in uploaded))
    if len(zips) + len(workbooks) + min(len(yamls), 1) > 1:
        raise UploadError(f"the upload mixes several cases ({names}); upload {EXPECTED}")
    if zips:
        return _from_zip(str(zips[0]), uploaded[zips[0]], budget)
    if workbooks:
        return read_case_workbook(uploaded[workbooks[0]], label=str(workbooks[0]), budget=budget)
    if len(yamls) == 1:
        return _from_files(yamls[0], uploaded.__getitem__, set(uploaded), budget,
                           lambda relative: [f'history file "{excerpt(relative, 80)}" is not among the uploaded '
                                             "files", f"the files uploaded are: {names}"])
    if len(yamls) > 1:
        raise UploadError(f"several YAML files ({names}); upload one case.yaml with its history CSV")
    raise UploadError(f"no case found in {names}; upload {EXPECTED}")


def _from_zip(name: str, data: bytes, budget: UploadBudget) -> Case:
    with open_zip(data, name, budget.limits) as archive:
        members = {upload_path(m.filename): m for m in archive.infolist()
                   if not m.is_dir() and "__MACOSX" not in m.filename}
        cases = [path for path in members if path.name == CASE_FILE]
        if not cases:
            found = ", ".join(excerpt(p, 80) for p in list(members)[:8]) or "nothing"
            raise UploadError(f"{name}: no {CASE_FILE} inside (found: {found})")
        if len(cases) > 1:
            raise UploadError(f"{name}: holds {len(cases)} {CASE_FILE} files; zip one case folder at a time")
        return _from_files(cases[0], lambda path: unzip(archive, members[path], name, budget), set(members), budget,
                           lambda relative: [f'{name}: history file "{excerpt(relative, 80)}" is not in the zip '
                                             f"beside {excerpt(cases[0], 80)}"])


def _from_files(case_file: PurePosixPath, read: Callable[[PurePosixPath], bytes], present: set[PurePosixPath],
                budget: UploadBudget, missing: Callable[[PurePosixPath], list[str]]) -> Case:
    """The case of ``case_file`` among uploaded files: ``read(path)`` gives a file's bytes."""
    data = read_case_yaml(read(case_file), case_file.name)
    budget.check_time(f"reading {case_file.name}")
    relative = history_path(data, case_file.name)
    target = case_file.parent / relative
    if target not in present:
        raise CaseError(missing(relative))
    limits = budget.limits
    history = history_of(data, lambda: History.from_csv(read(target), str(relative), max_rows=limits.history_rows,
                                                        max_columns=limits.history_columns))
    budget.check_time(f"reading {excerpt(relative, 80)}")
    case = parse_case(data, history)
    budget.check_time(f"checking {case_file.name}")
    return case
