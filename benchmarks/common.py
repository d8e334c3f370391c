"""What every benchmark records next to its numbers, and where it writes them.

Each benchmark writes one JSON file to ``benchmarks/results/<name>.json`` (atomically:
a temporary file, then a rename) holding the machine, the package versions, the date,
the git commit and the load average before and after, so numbers from different
machines or moments are never compared blindly.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import platform
import statistics
import subprocess
import sys
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
CASE = ROOT / "data" / "cases" / "paper"
PACKAGES = ("highspy", "pyomo", "numpy", "pandas", "scipy")
# Twelve delivery days spread over the year of the bundled history, and the case's own day.
DAYS = tuple(f"2025-{month:02d}-15" for month in range(1, 13))
QUICK_DAYS = ("2025-02-15", "2025-05-15", "2025-08-15", "2025-11-15")
STRATEGIES = ("deterministic", "optimistic", "balanced", "pessimistic")


def git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True, check=True).stdout.strip()
        return out.stdout.strip() + ("+uncommitted" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def load_average() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


def machine() -> dict:
    """Machine, interpreter and package versions."""
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {"python": platform.python_version(), "platform": platform.platform(), "machine": platform.machine(),
            "processor": platform.processor() or cpu_model(), "cores": os.cpu_count(), "packages": versions}


def cpu_model() -> str | None:
    """The processor's name and clock as the kernel reports them (``platform.processor()`` is
    often empty on Linux): two machines of one architecture can differ by half in solve times."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            fields = [line.split(":", 1) for line in info if ":" in line]
    except OSError:
        return None
    names = sorted({value.strip() for key, value in fields if key.strip() == "model name"})
    clocks = [float(value) for key, value in fields if key.strip() == "cpu MHz"]
    if not names:
        return None
    return ", ".join(names) + (f" at {max(clocks):.0f} MHz" if clocks else "")


def header(name: str, mode: str) -> dict:
    return {"benchmark": name, "mode": mode, "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "git_commit": git_commit(), "machine": machine(), "load_average_before": load_average()}


def write_result(document: dict, path: Path | None = None) -> Path:
    """Write ``document`` to ``path`` (default ``benchmarks/results/<benchmark>.json``) beside it
    first, then renamed into place, and return the path."""
    document["load_average_after"] = load_average()
    path = Path(path) if path is not None else RESULTS / f"{document['benchmark']}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    print(f"wrote {_shown(path)}", file=sys.stderr)
    return path


def _shown(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def summary(values: list[float]) -> dict:
    """Median, 90th percentile and maximum [s], rounded to milliseconds."""
    ordered = sorted(values)
    p90 = ordered[min(len(ordered) - 1, int(round(0.9 * (len(ordered) - 1))))]
    return {"median": round(statistics.median(ordered), 3), "p90": round(p90, 3), "max": round(ordered[-1], 3)}
