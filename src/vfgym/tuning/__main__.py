"""A sweep worker process (``python -m vfgym.tuning``): its job comes as JSON on stdin."""

import sys

from vfgym.tuning._workers import worker_main

if __name__ == "__main__":
    sys.exit(worker_main())
