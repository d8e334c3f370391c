"""``python -m rvpp data import|import-omie-intraday|build-case|import-workbook|band-quality``: real data in, a
case out."""

from __future__ import annotations

import argparse
import datetime as dt
import json
import sys

from ..data.case import PRICE_MODELS
from ..data.files import check_replaceable
from ..data.importers.omie_intraday import DEFAULT_PRESET as DEFAULT_INTRADAY_PRESET, PRESETS as INTRADAY_PRESETS
from ..errors import RvppError
from ..uncertainty.quality import SERIES
from .options import DEFAULT_CASE, Number, date_option, path_option

DEFAULT_TEMPLATE = DEFAULT_CASE


def add_data_commands(commands) -> None:
    """Add ``data`` with ``build``, ``import``, ``import-omie-intraday``, ``build-case``, ``import-workbook`` and
    ``band-quality``."""
    data = commands.add_parser("data", help="build the default dataset, import real data, build a case from it")
    commands = data.add_subparsers(title="data commands")
    build = commands.add_parser("build", help="regenerate the synthetic history of the paper case")
    build.add_argument("--seed", type=Number(0, whole=True), help="random seed >= 0 (default: the published one)")
    build.add_argument("--out", type=path_option, default=DEFAULT_CASE / "history.csv", help="CSV to write")
    build.set_defaults(run=_run_data_build)

    read = commands.add_parser(
        "import", help="read downloaded OMIE / ENTSO-E files and report what they hold",
        description="Read OMIE marginalpdbc files (or their zip archives), ENTSO-E Transparency Platform CSV "
                    "exports and hourly tables; print what each holds (span, periods, resolution, gaps, "
                    "duplicates, clock changes, units, zone) and optionally write them as one hourly CSV.")
    read.add_argument("files", nargs="+", type=path_option, metavar="FILE")
    read.add_argument("--zone", help="OMIE price zone ES (default) or PT; ENTSO-E area when a file holds several")
    read.add_argument("--out", type=path_option, metavar="CSV", help="write the series on one UTC hour grid "
                      "(time_utc, time_local, series...); quarter-hours are averaged to hours")
    read.set_defaults(run=_run_import)

    intraday = commands.add_parser(
        "import-omie-intraday", help="read OMIE intraday auction price files into a table or a case's history",
        description="Read OMIE marginalpibc files (marginalpibc_YYYYMMDDSS.V: day, session, version; or their zip "
                    "archives), print what each session holds, and write the prices as hourly columns "
                    "price_ida1, price_ida2, ... into a CSV table or into a case's history (hours before a "
                    "session's window hold the day-ahead price, as the case's provenance says).")
    intraday.add_argument("files", nargs="+", type=path_option, metavar="FILE")
    intraday.add_argument("--sessions", choices=INTRADAY_PRESETS, default=DEFAULT_INTRADAY_PRESET,
                          help="the sessions the files belong to: iberian_2024 (default: IDA1, IDA2, IDA3) or "
                               "tool_seven (IDM1 to IDM7, the seed paper's tool)")
    intraday.add_argument("--zone", default="ES", help="OMIE price zone ES (default) or PT")
    intraday.add_argument("--start", type=date_option, metavar="YYYY-MM-DD",
                          help="first delivery day asked for; a file of an earlier day is refused")
    intraday.add_argument("--end", type=date_option, metavar="YYYY-MM-DD",
                          help="last delivery day asked for; a file of a later day is refused")
    intraday.add_argument("--out", type=path_option, metavar="CSV", help="write the prices on one UTC hour grid "
                          "(time_utc, time_local, price_ida1, ...); quarter-hours are averaged to hours")
    intraday.add_argument("--case", type=path_option, metavar="FOLDER",
                          help="add the prices to the history of this case (its days are the days asked for)")
    intraday.add_argument("--force", action="store_true",
                          help="with --case: replace intraday price columns the history already holds")
    intraday.set_defaults(run=_run_import_intraday)

    build = commands.add_parser(
        "build-case", help="build a case folder from downloaded files",
        description="Build a case from imported series: real day-ahead prices, wind and PV from the fleet's "
                    "capacity factor (actual and day-ahead forecast), the CSP's solar-field heat from the real sky "
                    "(a clear-sky index of the solar series), electrical demands from the system load and its "
                    "forecast, thermal demands from a temperature series (--weather) or modelled; reserve prices "
                    "stay modelled. The case's provenance section says, per column, real, real-derived or "
                    "modelled.")
    build.add_argument("--from", dest="sources", nargs="+", type=path_option, required=True, metavar="FILE")
    build.add_argument("--out", type=path_option, required=True, metavar="FOLDER", help="case folder to write")
    build.add_argument("--template", type=path_option, default=DEFAULT_TEMPLATE,
                       help="case whose units and settings are used (default: the paper case)")
    build.add_argument("--errors-scale", type=Number(0), default=1.0, metavar="K",
                       help="scale the fleet's forecast error for a single farm: forecast = actual − "
                            "K·(actual − fleet forecast) (default 1)")
    build.add_argument("--start", help="first local day YYYY-MM-DD (default: the first whole day of the data)")
    build.add_argument("--end", help="last local day YYYY-MM-DD (default: the last whole day of the data)")
    build.add_argument("--date", help="delivery date of the case (default: the last day)")
    build.add_argument("--zone", help="OMIE price zone ES (default) or PT; ENTSO-E area")
    build.add_argument("--wind-capacity", type=Number(0, low_open=True, unit="MW"), metavar="MW",
                       help="fleet wind capacity (default: the highest output in the data)")
    build.add_argument("--solar-capacity", type=Number(0, low_open=True, unit="MW"), metavar="MW",
                       help="fleet solar capacity (default: the highest output in the data)")
    build.add_argument("--fill-gaps", type=Number(0, whole=True, unit="h"), default=0, metavar="HOURS",
                       help="interpolate gaps of at most HOURS hours linearly, each reported (default 0: refuse gaps)")
    build.add_argument("--bands", choices=("forecast", "climatology"), default="forecast",
                       help="forecast (default): wind, PV and DAM price on forecast-error bands; climatology: "
                            "every source on the paper's bands")
    build.add_argument("--sky", choices=("real", "modelled"), default="real",
                       help="the CSP's solar-field heat from the real sky (default: the solar series' clear-sky "
                            "index) or the modelled one (synthetic DNI, climatology bands)")
    build.add_argument("--demands", choices=("real", "modelled"), default="real",
                       help="electrical demands from the system load (default, when the files give it) or the "
                            "synthetic series")
    build.add_argument("--seed", type=Number(0, whole=True), help="seed of the synthetic series >= 0 "
                       "(default: the published one)")
    build.add_argument("--force", action="store_true",
                       help="overwrite the case.yaml and history.csv of a folder that already holds them")
    _add_weather_options(build)
    build.set_defaults(run=_run_build_case)

    workbook = commands.add_parser(
        "import-workbook", help="write a case from the workbook of the authors' RVPP tool",
        description="Read the workbook of the seed paper's authors' tool (RVPP_data.xlsx: the inputs of its "
                    "day-ahead session) and write an rvpp case folder: its units, prices, bands and budgets. "
                    "The workbook gives one day; the case holds a six-day window whose percentiles are the "
                    "workbook's bands. docs/gams-tool.md lists every mapping and every model difference.")
    workbook.add_argument("workbook", type=path_option, metavar="XLSX")
    workbook.add_argument("--out", type=path_option, required=True, metavar="FOLDER", help="case folder to write")
    workbook.add_argument("--date", type=date_option, required=True, metavar="YYYY-MM-DD",
                          help="delivery date to place the workbook's day on (the workbook has none)")
    workbook.add_argument("--force", action="store_true",
                          help="overwrite the case.yaml and history.csv of a folder that already holds them")
    workbook.set_defaults(run=_run_import_workbook)

    quality = commands.add_parser(
        "band-quality", help="width, misses and shortfall of climatology and forecast bands",
        description="Compare the paper's climatology bands with forecast-error bands on real data: for every "
                    "day, bands from the window before it, scored against the day's actual values "
                    "(capacity-normalised for output).")
    quality.add_argument("files", nargs="+", type=path_option, metavar="FILE")
    quality.add_argument("--series", choices=SERIES, default="wind_onshore",
                         help="wind_onshore (default), solar or price_da")
    quality.add_argument("--year", type=Number(1900, 2200, whole=True),
                         help="score the days of this year (default: the last whole year)")
    quality.add_argument("--window", type=Number(1, 366, whole=True, unit="days"), default=30,
                         help="window [days] (default 30)")
    quality.add_argument("--q-lo", type=Number(0, 0.5, low_open=True, high_open=True), default=0.2,
                         help="lower quantile (default 0.2)")
    quality.add_argument("--q-hi", type=Number(0.5, 1, low_open=True, high_open=True), default=0.8,
                         help="upper quantile (default 0.8)")
    quality.add_argument("--price-model", choices=PRICE_MODELS, default="same_hour_yesterday",
                         help="point forecast of prices (default same_hour_yesterday)")
    quality.add_argument("--zone", help="OMIE price zone ES (default) or PT")
    quality.add_argument("--json", action="store_true", help="print the numbers as JSON")
    quality.set_defaults(run=_run_band_quality)


def _run_import(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..data.importers import TABLE_HEADER, hourly_table, import_files, write_table

    if args.out:
        check_replaceable(args.out, (TABLE_HEADER,), "a table rvpp wrote")
    imports = import_files(args.files, args.zone)
    for item in imports:
        print("\n".join(item.report.lines()))
    if args.out:
        table = hourly_table(imports)
        for note in table.notes:
            print(f"note: {note}", file=sys.stderr)
        write_table(table.frame, args.out)
        print(f"wrote {len(table.frame)} hours of {', '.join(table.frame.columns)} to {args.out}", file=sys.stderr)
    return 0


def _run_import_intraday(args: argparse.Namespace) -> int:
    # heavy (the case model and pandas' readers): loaded only when this command runs
    from ..data.importers import TABLE_HEADER, hourly_table, write_table
    from ..data.importers.omie_intraday import read
    from ..data.intraday_prices import add_intraday_prices

    if args.case and (args.start or args.end):
        raise RvppError("--start and --end cannot be given with --case: the case's history gives the days")
    if args.out:
        check_replaceable(args.out, (TABLE_HEADER,), "a table rvpp wrote")
    if args.case:
        added = add_intraday_prices(args.files, args.case, preset=args.sessions, zone=args.zone,
                                    overwrite=args.force)
        for report in added.reports:
            print("\n".join(report.lines()))
        print("\n".join(added.lines()))
        table = added.table
    else:
        imports = read(args.files, args.sessions, args.zone, days=_asked_days(args.start, args.end))
        for item in imports:
            print("\n".join(item.report.lines()))
        table = hourly_table(imports)
    if args.out:
        for note in table.notes:
            print(f"note: {note}", file=sys.stderr)
        write_table(table.frame, args.out)
        print(f"wrote {len(table.frame)} hours of {', '.join(table.frame.columns)} to {args.out}", file=sys.stderr)
    return 0


def _asked_days(start: str | None, end: str | None) -> tuple[dt.date | None, dt.date | None] | None:
    """The delivery days asked for by ``--start`` and ``--end`` (either may be open)."""
    if start is None and end is None:
        return None
    first = dt.date.fromisoformat(start) if start else None
    last = dt.date.fromisoformat(end) if end else None
    if first and last and first > last:
        raise RvppError(f"--start {start} is after --end {end}; give the first day first")
    return first, last


def _run_build_case(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..data.build_case import BuildOptions, build_case

    options = BuildOptions(errors_scale=args.errors_scale, start=args.start, end=args.end, date=args.date,
                           zone=args.zone, wind_capacity_mw=args.wind_capacity,
                           solar_capacity_mw=args.solar_capacity, seed=args.seed, fill_gaps_h=args.fill_gaps,
                           bands=args.bands, sky=args.sky, demands=args.demands, **_weather_options(args))
    built = build_case(args.sources, args.out, template=args.template, options=options, overwrite=args.force,
                       progress=lambda m: print(f"  {m}", file=sys.stderr))
    print("\n".join(built.lines()))
    return 0


def _add_weather_options(build) -> None:
    """``build-case``'s options for thermal demands that follow a temperature series."""
    build.add_argument("--weather", type=path_option, metavar="CSV",
                       help="weather CSV with a time and an air temperature [°C] column (and optionally its "
                            "day-ahead forecast): thermal demands follow its heating degree-hours (default: "
                            "modelled)")
    build.add_argument("--weather-columns", nargs="+", default=(), metavar="ROLE=COLUMN",
                       help="name the weather file's columns: time=..., temperature=..., forecast=... (default: "
                            "found by name, e.g. time/timestamp, temperature/temp/t2m)")
    build.add_argument("--weather-timezone", metavar="TZ",
                       help="clock of weather times written without a UTC offset, e.g. UTC or Europe/Madrid")
    build.add_argument("--heating-base", type=Number(-90, 60, unit="°C"), metavar="C",
                       help="base temperature of the heating degree-hours max(0, base − T) (default 15.5 °C)")
    build.add_argument("--heat-base-share", type=Number(0, 1, low_open=True), metavar="SHARE",
                       help="share of a thermal demand that does not depend on the weather, in an hour of "
                            "average heating (default 0.5)")


def _weather_options(args: argparse.Namespace) -> dict:
    """The weather options given (the library's defaults stand for the others)."""
    given = {"weather": args.weather, "weather_columns": tuple(args.weather_columns),
             "weather_timezone": args.weather_timezone, "heating_base_c": args.heating_base,
             "heat_base_share": args.heat_base_share}
    return {name: value for name, value in given.items() if value is not None}


def _run_import_workbook(args: argparse.Namespace) -> int:
    # heavy (openpyxl): loaded only when this command runs
    from ..data.importers.gams_import import import_workbook

    made = import_workbook(args.workbook, args.out, dt.date.fromisoformat(args.date), overwrite=args.force)
    print("\n".join(made.lines()))
    return 0


def _run_band_quality(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..uncertainty.quality import band_quality_from_files

    table = band_quality_from_files(args.files, series=args.series, year=args.year, window_days=args.window,
                                    q_lo=args.q_lo, q_hi=args.q_hi, price_model=args.price_model, zone=args.zone)
    if args.json:
        print(json.dumps(table, indent=2))
    else:
        for line in _quality_lines(table):
            print(line)
    return 0


def _quality_lines(table: dict) -> list[str]:
    unit = table["unit"]
    lines = [f"{table['series']} {table['year']}: {table['days']} days, {table['hours']} hours, "
             f"window {table['window_days']} days, band {table['q_lo']:g}-{table['q_hi']:g}"
             + (f", capacity {table['capacity']:,.0f} MW" if table.get("capacity") else "")]
    for method, row in table["methods"].items():
        lines.append(f"  {method:>12}: width {row['width']:.2f} {unit}, miss {row['miss_rate'] * 100:.1f} % "
                     f"(below {row['below_rate'] * 100:.1f} %, above {row['above_rate'] * 100:.1f} %), "
                     f"mean shortfall below the lower bound {row['shortfall']:.2f} {unit}")
    return lines


def _run_data_build(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..data import synth

    seed = synth.DEFAULT_SEED if args.seed is None else args.seed
    check_replaceable(args.out, (synth.HISTORY_HEADER,), "a history CSV")
    frame = synth.write_history(args.out, seed=seed)
    print(f"wrote {len(frame)} hours to {args.out} (seed {seed})", file=sys.stderr)
    return 0
