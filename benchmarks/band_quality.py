"""Quality of the bands on real Spanish data: climatology against forecast-error bands.

For every day of a year, bands are drawn as a plan for that day draws them (the 30 days
before it; the forecast issued for it) and scored against the day's actual values: mean
width, miss rate (share of hours outside the 20-80 % band; 40 % if calibrated) and mean
shortfall below the lower bound. Output series are in % of the year's highest output.

Besides rvpp's two methods the forecast band is also scored with its error quantiles
taken per clock hour instead of per forecast level, the alternative docs/model.md
compares. Writes ``benchmarks/results/band_quality.json`` (see ``benchmarks/common.py``)
and prints a table; needs the real data (``RVPP_SPAIN_DATA`` or ``../shared/data/spain``)
and skips what is absent. About three minutes on two busy cores.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import header, write_result  # noqa: E402
from rvpp.data.history import History  # noqa: E402
from rvpp.data.importers import fill_gaps, hourly_table, import_files  # noqa: E402
from rvpp.data.periods import delivery_periods  # noqa: E402
from rvpp.uncertainty.forecast import BandSpec, forecast_and_errors  # noqa: E402
from rvpp.uncertainty.quality import MAX_FILLED_GAP_H, band_quality_from_files, score  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SPAIN = Path(os.environ.get("RVPP_SPAIN_DATA", ROOT.parent / "shared" / "data" / "spain"))
RUNS = (  # (file, series, year)
    ("entsoe_spain_2015_2018.csv", "wind_onshore", 2018),
    ("entsoe_spain_2015_2018.csv", "solar", 2018),
    ("omie_spain_prices_2018_2025.csv", "price_da", 2019),
    ("omie_spain_prices_2018_2025.csv", "price_da", 2023),
    ("omie_spain_prices_2018_2025.csv", "price_da", 2024),
)
COLUMNS = {"wind_onshore": ("actual_wind_onshore", "forecast_wind_onshore"),
           "solar": ("actual_solar", "forecast_solar"), "price_da": ("price_da", None)}
TZ = "Europe/Madrid"
WINDOW, Q_LO, Q_HI = 30, 0.2, 0.8


def per_clock_hour(path: Path, series: str, year: int, capacity: float | None) -> dict:
    """The forecast band with error quantiles per clock hour (30 errors each), scored like rvpp's."""
    column, forecast = COLUMNS[series]
    table = hourly_table(import_files([path])).frame
    needed = [c for c in (column, forecast) if c]
    first, last = dt.date(year, 1, 1), dt.date(year, 12, 31)
    part = table.loc[(table.index.tz_convert(TZ).date >= first - dt.timedelta(days=WINDOW + 7))
                     & (table.index.tz_convert(TZ).date <= last), needed]
    part, _ = fill_gaps(part, MAX_FILLED_GAP_H)
    scale = 100.0 / capacity if capacity else 1.0
    spec = BandSpec(column, scale, "forecast", forecast_column=forecast,
                    price_model=None if forecast else "same_hour_yesterday",
                    low=0.0 if capacity else None, high=100.0 if capacity else None)
    history = History(part.reset_index(names="timestamp"))
    lows, highs, actual = [], [], []
    day = first
    while day <= last:
        periods = delivery_periods(day, TZ, 1.0)
        point, errors = forecast_and_errors(history, day, spec, n_days=WINDOW, timezone=TZ)
        quantiles = {h: np.quantile(g["error"].dropna(), (Q_LO, Q_HI)) for h, g in errors.groupby("hour")}
        f = point.reindex(periods.tz_convert("UTC")).to_numpy(float)
        lo = f + np.array([quantiles[h][0] for h in periods.hour])
        hi = f + np.array([quantiles[h][1] for h in periods.hour])
        if capacity:
            lo, hi = np.clip(lo, 0.0, 100.0), np.clip(hi, 0.0, 100.0)
        lows.append(lo)
        highs.append(hi)
        actual.append(history.days(day, 1, TZ)[column].to_numpy(float) * scale)
        day += dt.timedelta(days=1)
    return score(np.concatenate(lows), np.concatenate(highs), np.concatenate(actual))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="wind 2018 only")
    args = parser.parse_args()
    report = {**header("band_quality", "quick" if args.quick else "full"),
              "window_days": WINDOW, "q_lo": Q_LO, "q_hi": Q_HI, "runs": []}
    for file, series, year in RUNS[:1] if args.quick else RUNS:
        path = SPAIN / file
        if not path.is_file():
            print(f"skipped {series} {year}: {file} not found", file=sys.stderr)
            continue
        started = time.perf_counter()
        result = band_quality_from_files([path], series=series, year=year, window_days=WINDOW, q_lo=Q_LO, q_hi=Q_HI)
        result["methods"]["forecast_per_clock_hour"] = per_clock_hour(path, series, year, result["capacity"])
        result["seconds"] = round(time.perf_counter() - started, 1)
        for row in result["methods"].values():
            for key, value in row.items():
                row[key] = round(value * (100 if key.endswith("rate") else 1), 2)
        report["runs"].append(result)
        print(f"{series} {year}: done in {result['seconds']} s", file=sys.stderr, flush=True)
    write_result(report)
    for run in report["runs"]:
        print(f"{run['series']} {run['year']} [{run['unit']}; rates in %]")
        for method, row in run["methods"].items():
            print(f"  {method:<24} width {row['width']:>7.2f}  miss {row['miss_rate']:5.1f}  "
                  f"shortfall {row['shortfall']:6.2f}")


if __name__ == "__main__":
    main()
