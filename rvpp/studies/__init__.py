"""The paper's case studies, out-of-sample evaluation and the stochastic benchmark.

Every study is a function ``run(case, settings, executor=None, progress=None)`` that
returns a :class:`~rvpp.studies.runner.StudyOutput` (plain DataFrames, Plotly figures
and the facts the report checks); a dashboard page calls it with a ``progress(stage,
done, total)`` callback. :func:`run_studies` runs several of them and writes the
outputs; ``python -m rvpp study NAME`` is the command line. ``reproduce`` runs the
studies of the paper and the rolling backtest with its recommended Γ (beyond the paper);
the stress test (beyond the paper) runs on request.
"""

from ..lazy import lazy_names

_EXPORTS = {"STUDIES": ".run", "run_studies": ".run", "REPRODUCE": ".settings", "StudySettings": ".settings",
            "StudyOutput": ".runner"}

__all__ = sorted(_EXPORTS)


# Names are imported on first use (as in rvpp): the settings, which the command line reads to build
# its options, load without the studies and their solver stack.
__getattr__, __dir__ = lazy_names(__name__, _EXPORTS)
