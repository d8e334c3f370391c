"""``python -m dashboard [streamlit options]``: the dashboard as ``make run`` starts it (:mod:`.serve`)."""

import sys

from dashboard.serve import main

if __name__ == "__main__":  # a process multiprocessing starts imports this file again: it must not serve
    main(sys.argv[1:])
