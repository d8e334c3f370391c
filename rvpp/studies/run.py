"""Running studies by name: :data:`STUDIES` and :func:`run_studies` (see :mod:`rvpp.studies`)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import Executor
from pathlib import Path

from ..data.case import Case
from . import backtest, case1, markets, out_of_sample, sensitivity, stochastic, strategies, stress
from .report import write_all
from .runner import Progress, StudyOutput
from .settings import REPRODUCE, REPRODUCE_STUDIES, StudySettings

STUDIES = {  # in the order of settings.STUDY_NAMES, the names the command line offers
    "case1": case1.run,
    "strategies": strategies.run,
    "sensitivity": sensitivity.run,
    "markets": markets.run,
    "out-of-sample": out_of_sample.run,
    "stochastic": stochastic.run,
    "stress": stress.run,
    "backtest": backtest.run,
}


def run_studies(case: Case, names: Sequence[str], settings: StudySettings, out: str | Path | None = None,
                executor: Executor | None = None, progress: Progress | None = None,
                scheduler: str = "serial") -> list[StudyOutput]:
    """Run the named studies (``reproduce``: those of the paper and the backtest) and, with ``out``, write
    their outputs."""
    started = time.perf_counter()
    chosen = list(REPRODUCE_STUDIES) if REPRODUCE in names else list(names)
    outputs = [STUDIES[name](case, settings, executor, progress) for name in chosen]
    if out is not None:
        write_all(outputs, out, case, settings,
                  {"scheduler": scheduler, "wall_s": time.perf_counter() - started, "studies_run": chosen})
    return outputs
