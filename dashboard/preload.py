"""What the fork server of :mod:`dashboard.solving` imports, once, for every solver process.

A solver process is forked from the fork server, so it starts with whatever the fork
server imported. Importing the solve and sweep modules brings Pyomo and HiGHS; Pyomo
imports SciPy only on first use, which would cost every solver process most of a second
(measured 0.8-0.9 s on two busy cores, more than the solve of the default day), so
it is done here. Nothing is solved here: a solver started in the fork server could leave
threads behind that forked processes must not inherit.
"""

from pyomo.common.dependencies import scipy_available

import dashboard.worker  # noqa: F401  (the solver processes' entry points)
import rvpp.service  # noqa: F401  (loads the solver stack before the first solve)

bool(scipy_available)  # Pyomo's deferred import of SciPy, done now
