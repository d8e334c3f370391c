"""The paper's case studies, out-of-sample evaluation and the stochastic benchmark.

Every study is a function ``run(case, settings, executor=None, progress=None)`` that
returns a :class:`~rvpp.studies.runner.StudyOutput` (plain DataFrames, Plotly figures
and the facts the report checks); a dashboard page calls it with a ``progress(stage,
done, total)`` callback. :func:`run_studies` runs several of them and writes the
outputs; ``python -m rvpp study NAME`` is the command line. ``reproduce`` runs the
studies of the paper and the rolling backtest with its recommended Γ (beyond the paper);
the stress test (beyond the paper) runs on request.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import Executor
from pathlib import Path

from ..data.case import Case
from . import backtest, case1, markets, out_of_sample, sensitivity, stochastic, strategies, stress
from .report import write_all
from .runner import Progress, StudyOutput
from .settings import StudySettings

STUDIES = {
    "case1": case1.run,
    "strategies": strategies.run,
    "sensitivity": sensitivity.run,
    "markets": markets.run,
    "out-of-sample": out_of_sample.run,
    "stochastic": stochastic.run,
    "stress": stress.run,
    "backtest": backtest.run,
}
REPRODUCE = "reproduce"
PAPER_STUDIES = ("case1", "strategies", "sensitivity", "markets", "out-of-sample", "stochastic")
REPRODUCE_STUDIES = (*PAPER_STUDIES, "backtest")  # the paper's, then the rolling backtest beyond it

__all__ = ["REPRODUCE", "STUDIES", "StudyOutput", "StudySettings", "run_studies"]


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
