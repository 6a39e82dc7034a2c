"""A sweep worker process (``python -m vfgym.tuning``): its job comes as JSON on stdin."""

from __future__ import annotations

import json
import signal
import sys
import warnings
from dataclasses import asdict

from vfgym.moves.axis import AxisNote
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._storage import StorageSpec
from vfgym.tuning._workers import run_worker


def _worker_main() -> int:
    """Entry of a worker process (``python -m vfgym.tuning``): its job as JSON on stdin."""
    warnings.simplefilter("ignore", AxisNote)  # the parent process says it once
    job = json.loads(sys.stdin.read())
    cfg = SweepConfig(**job["config"])
    spec = StorageSpec(**job["storage"])
    try:
        rep = run_worker(cfg, spec, job["study"], job["index"])
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        return 130
    print(json.dumps(asdict(rep)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(_worker_main())
