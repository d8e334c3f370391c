"""Cases as files to upload or download: a zip of a case folder, a ``case.yaml`` with its
history CSV, or an Excel case workbook (:mod:`rvpp.outputs.workbook`).

:func:`read_case_files` takes the files as ``{file name: bytes}`` and returns a validated
:class:`~rvpp.data.case.Case`; anything wrong raises :class:`~rvpp.errors.CaseError` with a
message meant for the person who uploaded the files.
"""

from __future__ import annotations

import io
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path, PurePosixPath

from ..data.case import CASE_FILE, Case, load_case, save_case
from ..errors import CaseError
from .workbook import read_case_workbook

MAX_UNZIPPED_BYTES = 200 * 1024 ** 2  # refuse archives that inflate beyond 200 MiB
YAML_SUFFIXES = (".yaml", ".yml")
EXPECTED = ("a zip of a case folder, a case.yaml together with its history CSV, or an Excel case "
            "workbook (.xlsx)")


def case_zip_bytes(case: Case, folder_name: str | None = None) -> bytes:
    """``case.yaml`` and ``history.csv`` of ``case`` in a zip, inside one folder."""
    folder_name = folder_name or case.name
    buffer = io.BytesIO()
    with tempfile.TemporaryDirectory() as tmp:
        folder = save_case(case, Path(tmp) / "case")
        with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(folder.iterdir()):
                archive.write(path, arcname=f"{folder_name}/{path.name}")
    return buffer.getvalue()


def read_case_files(files: Mapping[str, bytes]) -> Case:
    """A case from uploaded files (see the module docstring for the accepted forms)."""
    if not files:
        raise CaseError(f"no file given; upload {EXPECTED}")
    names = {PurePosixPath(name).name: data for name, data in files.items()}
    suffixes = {name: PurePosixPath(name).suffix.lower() for name in names}
    zips = [n for n, s in suffixes.items() if s == ".zip"]
    workbooks = [n for n, s in suffixes.items() if s in (".xlsx", ".xlsm")]
    yamls = [n for n, s in suffixes.items() if s in YAML_SUFFIXES]
    if len(zips) + len(workbooks) + min(len(yamls), 1) > 1:
        raise CaseError(f"the upload mixes several cases ({', '.join(sorted(names))}); upload {EXPECTED}")
    if zips:
        return _from_zip(zips[0], names[zips[0]])
    if workbooks:
        return read_case_workbook(names[workbooks[0]], label=workbooks[0])
    if len(yamls) == 1:
        with tempfile.TemporaryDirectory() as tmp:
            for name, data in names.items():
                (Path(tmp) / name).write_bytes(data)
            return _load(Path(tmp) / yamls[0], uploaded=sorted(names))
    if len(yamls) > 1:
        raise CaseError(f"several YAML files ({', '.join(sorted(yamls))}); upload one case.yaml with its history CSV")
    raise CaseError(f"no case found in {', '.join(sorted(names))}; upload {EXPECTED}")


def _from_zip(name: str, data: bytes) -> Case:
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
        raise CaseError(f"{name}: not a valid zip archive") from None
    with archive:
        members = [m for m in archive.infolist() if not m.is_dir()]
        if sum(m.file_size for m in members) > MAX_UNZIPPED_BYTES:
            raise CaseError(f"{name}: unpacks to more than {MAX_UNZIPPED_BYTES // 1024 ** 2} MiB; "
                            "a case is usually a few MiB")
        cases = [m for m in members if PurePosixPath(m.filename).name == CASE_FILE
                 and "__MACOSX" not in m.filename]
        if not cases:
            raise CaseError(f"{name}: no {CASE_FILE} inside (found: "
                            f"{', '.join(m.filename for m in members[:8]) or 'nothing'})")
        if len(cases) > 1:
            raise CaseError(f"{name}: holds {len(cases)} {CASE_FILE} files; zip one case folder at a time")
        folder = PurePosixPath(cases[0].filename).parent
        with tempfile.TemporaryDirectory() as tmp:
            for member in members:
                path = PurePosixPath(member.filename)
                if path.parent != folder:
                    continue
                (Path(tmp) / path.name).write_bytes(archive.read(member))
            return _load(Path(tmp) / CASE_FILE, uploaded=[PurePosixPath(m.filename).name for m in members])


def _load(path: Path, uploaded: list[str]) -> Case:
    try:
        return load_case(path)
    except CaseError as err:
        missing = [p for p in err.problems if "does not exist" in p]
        if missing:
            raise CaseError([*err.problems, f"the files uploaded are: {', '.join(uploaded)}"]) from None
        raise
