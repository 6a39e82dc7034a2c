"""A sweep as one call, :func:`sweep`: the run folder made, the study created or continued,
its workers run (one in the calling process, or several processes beside it), and what
the run found written to the folder and returned as a :class:`SweepResult`. ``vfgym
sweep`` parses its options into a :class:`~vfgym.tuning.SweepConfig`, calls it and prints
the result; a notebook calls it the same way.
"""

from __future__ import annotations

import json
import shlex
import shutil
import signal
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from vfgym._validate import check_output_path
from vfgym.axis import AXIS_FILE, write_axis
from vfgym.io.runs import read_yaml, write_text, write_yaml
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_SETTINGS
from vfgym.report import (
    Report,
    Verdict,
    axis_verdict,
    compact_rows,
    format_compact,
    format_verdict,
)
from vfgym.scoring import evaluate
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import stored_result
from vfgym.tuning._results import (
    BestRecord,
    FoundReference,
    against_paper,
    best_of,
    best_record,
    best_trial,
    find_reference,
    gap_pct,
    paper_cost,
    trial_settings,
    write_plots,
    write_trials_csv,
)
from vfgym.tuning._storage import StorageSpec, mask_url, open_storage, resolve_storage
from vfgym.tuning._study import check_sampler, create_or_load, trial_budget
from vfgym.tuning._workers import (
    RETRY,
    WorkerReport,
    prepare_model,
    run_processes,
    run_worker,
)

if TYPE_CHECKING:
    from optuna import Study
    from optuna.storages import BaseStorage


class TrialCounts(NamedTuple):
    """A study's trials by state.

    Attributes
    ----------
    complete, running, waiting, fail, pruned : int
        The trials in each state.
    """

    complete: int = 0
    running: int = 0
    waiting: int = 0
    fail: int = 0
    pruned: int = 0

    @classmethod
    def of(cls, study: Study) -> TrialCounts:
        """The study's trials counted.

        Parameters
        ----------
        study : optuna.Study
            The study.

        Returns
        -------
        TrialCounts
            Its trials by state.
        """
        out = dict.fromkeys(cls._fields, 0)
        for t in study.get_trials(deepcopy=False):
            out[t.state.name.lower()] += 1
        return cls(**out)


class SweepStart(NamedTuple):
    """What :func:`sweep` opened, told before its first trial.

    Attributes
    ----------
    study : str
        The study's name (also its run folder's).
    created : bool
        Whether the study is new (else continued).
    complete : int
        Its completed trials before this run.
    budget : int
        The completed trials it ends with.
    storage : str
        Where it lives (a password masked).
    run_dir : pathlib.Path
        The run folder.
    scenarios : tuple of str
        The scenarios' names.
    """

    study: str
    created: bool
    complete: int
    budget: int
    storage: str
    run_dir: Path
    scenarios: tuple[str, ...]


class SweepProgress(NamedTuple):
    """How far a sweep is, told at most once a second while it runs and once at the end.

    Attributes
    ----------
    complete : int
        Completed trials of the study.
    budget : int
        The completed trials it ends with.
    best_cost : float or None
        The best trial's cost (:func:`~vfgym.tuning.best_trial`); None before one.
    best_feasible : bool
        Whether the best trial is feasible.
    final : bool
        Whether the trials have ended (the last report).
    """

    complete: int
    budget: int
    best_cost: float | None
    best_feasible: bool
    final: bool


@dataclass(frozen=True, eq=False)
class SweepResult:
    """What :func:`sweep` did and found; its run folder holds the same.

    Attributes
    ----------
    config : SweepConfig
        The configuration.
    study : optuna.Study
        The study (open on its storage).
    run_dir : pathlib.Path
        The run folder: config.yaml, axis.yaml, command.txt, trials.csv, best.yaml,
        summary.yaml, report.txt, the plots and (by default) the storage.
    storage : StorageSpec
        Where the study lives.
    created : bool
        Whether this run created the study.
    counts : TrialCounts
        The study's trials by state at the end.
    budget : int
        The completed trials it ends with.
    elapsed_s : float
        Wall seconds of the trials of this run.
    workers : tuple of WorkerReport
        Each worker's report with its exit status (none if interrupted in this process).
    retried : tuple of int
        The trials of this run that repeat a dead or interrupted worker's.
    best : BestRecord or None
        The best trial as ``best.yaml`` holds it; None before a trial completes.
    comparison : Report or None
        The tuned settings against the paper's on the scenarios.
    verdict : Verdict or None
        The held-out verdict on the axis's test moves (not after an interrupt).
    plots : dict or None
        Each figure's file, or why it was skipped.
    interrupted : bool
        Whether Ctrl-C stopped the trials (every finished trial is kept).
    unfinished : bool
        Whether the workers ended before the study held its trials (not by the timeout
        or an interrupt): running it again continues it.
    """

    config: SweepConfig
    study: Study
    run_dir: Path
    storage: StorageSpec
    created: bool
    counts: TrialCounts
    budget: int
    elapsed_s: float
    workers: tuple[WorkerReport, ...]
    retried: tuple[int, ...]
    best: BestRecord | None
    comparison: Report | None
    verdict: Verdict | None
    plots: dict[str, str] | None
    interrupted: bool
    unfinished: bool

    def as_dict(self) -> dict[str, Any]:
        """``summary.yaml``'s mapping.

        Returns
        -------
        dict
            The study, storage, trials by state, budget, seconds, workers, retried trials,
            and (when known) the best, the comparison, the plots and the verdict.
        """
        out: dict[str, Any] = {
            "study": self.study.study_name,
            "storage": self.storage.display,
            "trials": self.counts._asdict(),
            "budget": self.budget,
            "elapsed_s": round(self.elapsed_s, 3),
            "workers": [asdict(w) for w in self.workers],
            "retried": list(self.retried),
        }
        if self.best is not None and self.comparison is not None:
            out["best"] = self.best.as_dict()
            out["comparison"] = compact_rows(self.comparison).as_dict()
        if self.plots is not None:
            out["plots"] = self.plots
        if self.verdict is not None:
            out["verdict"] = self.verdict.to_dict()
        return out

    def text(self) -> str:
        """The report as ``vfgym sweep`` prints it (``report.txt``).

        Returns
        -------
        str
            The trials, this run's workers, the best against the paper's settings (and a
            grid reference), the table by scenario, the plots, and the held-out verdict.
        """
        lines = [self._trials_line()]
        if self.workers:
            lines.append(self._workers_line())
        lines += self._best_lines()
        if self.plots is not None:
            lines.append("plots: " + ", ".join(f"{k} {v}" for k, v in self.plots.items()))
        if self.unfinished:
            stops = sorted({w.stopped for w in self.workers})
            lines.append(
                f"the study is not finished ({self.counts.complete}/{self.budget}): the "
                f"workers ended ({', '.join(stops) or 'no report'}); run the same command "
                "again to continue"
            )
        if self.verdict is not None:  # the report ends with the held-out verdict
            lines += ["", format_verdict(self.verdict, axis_file=self.config.axis_file)]
        return "\n".join(lines)

    def _trials_line(self) -> str:
        n, budget = self.counts, self.budget
        done = (
            f"{n.complete}/{budget} completed trials"
            if n.complete <= budget
            else f"{n.complete} completed trials (--trials {budget} asked)"
        )
        return (
            f"study {self.study.study_name}: {done} "
            f"({n.fail} failed, {n.running} running, {n.waiting} waiting"
            + (f", {n.pruned} pruned: over the budget" if n.pruned else "")
            + f") in {self.elapsed_s:.1f} s"
        )

    def _workers_line(self) -> str:
        sims = sum(w.simulated for w in self.workers)
        ran = sum(len(w.trials) for w in self.workers)
        return (
            f"this run: {ran} trials by {len(self.workers)} worker(s), {sims} simulated "
            f"({ran - sims} repeated settings copied)"
            + (f", failed trials retried: {list(self.retried)}" if self.retried else "")
            + (f"; worker exits {[w.exit for w in self.workers]}" if len(self.workers) > 1 else "")
        )

    def _best_lines(self) -> list[str]:
        b = self.best
        if b is None or self.comparison is None:
            return ["no completed trial yet"]
        paper = float("nan") if b.paper_cost is None else b.paper_cost
        lines = [
            f"best: trial {b.trial}, {self.config.aggregate_label()} cost {b.cost:.4f} "
            f"({'feasible' if b.feasible else 'INFEASIBLE'}) against the paper's "
            f"{paper:.4f} ({gap_pct(b.cost, paper):+.1f} %)"
        ]
        if b.reference is not None:
            lines.append(
                f"gap to the grid reference {b.reference.path} (cost "
                f"{b.reference.cost:.4f}): {b.reference.gap_pct:+.2f} %"
            )
        s = b.settings
        lines.append(
            f"settings: value {s['value_rad']:.6g} rad, error limit {s['error_limit_rad']:.6g} "
            f"rad, k {s['k']:.6g}, Ts/Tf {s['ts_over_tf']:.4g}, law {s['accel_law']}"
        )
        return [*lines, "", format_compact(self.comparison)]


def sweep(
    config: SweepConfig,
    *,
    stem: str = "sweep",
    argv: Sequence[str] | None = None,
    on_start: Callable[[SweepStart], object] | None = None,
    on_progress: Callable[[SweepProgress], object] | None = None,
) -> SweepResult:
    """Run a sweep: create its study (or continue it), run its workers until the study
    holds ``config.trials`` completed trials, and write and return what it found.

    The run folder is ``RUNS_DIR/sweep/STUDY/``; a study of the same name continues (in
    the same storage only). With one worker the trials run in this process, with more in
    as many processes. Ctrl-C stops the trials, keeping every finished one: the files
    are written and the result says ``interrupted``.

    Parameters
    ----------
    config : SweepConfig
        What to run.
    stem : str
        The default study name's first part (``STEM-YYYYmmdd-HHMMSS``), when
        ``config.study`` is None.
    argv : sequence of str or None
        The command line to record in ``command.txt`` (after ``vfgym``; a password
        masked); default: the configuration's options.
    on_start : callable or None
        Called with a :class:`SweepStart` once the study is open, before the trials.
    on_progress : callable or None
        Called with a :class:`SweepProgress` at most once a second while the trials
        run, and once when they end (each call reads the study).

    Returns
    -------
    SweepResult
        What the run did and found.

    Raises
    ------
    ValueError
        Naming the option, if the storage cannot be used for this run folder, the study
        of that name optimises another problem, or a grid reference given is not one.
    """
    cfg = config
    prepare_model(cfg)  # the compass's model imports, on a thread from now on
    scenarios = cfg.scenario_list()
    check_sampler(cfg)
    name = cfg.study or _default_study(stem, cfg.runs_dir)
    run_dir = Path(cfg.runs_dir) / "sweep" / name
    check_output_path("runs_dir", run_dir, folder=True, shown=cfg.runs_dir, root=cfg.runs_dir)
    spec = resolve_storage(cfg.storage, run_dir)
    _check_storage_file(cfg.storage, spec)
    _check_same_storage(run_dir, spec.display)
    reference = (  # a grid's reference is a mean cost
        find_reference(cfg.reference, cfg.runs_dir, scenarios, cfg.laws, cfg.axis_key())
        if cfg.aggregate == "mean"
        else None
    )
    warm = _warm_up(cfg, scenarios) if cfg.workers == 1 else None
    try:
        storage, study, created = _open_study(cfg, spec, name, run_dir, scenarios)
        _record(run_dir, cfg, name, spec, argv)
    finally:
        if warm is not None:
            warm.join()
    before = TrialCounts.of(study)
    budget = trial_budget(cfg)
    if on_start is not None:
        names = tuple(s.name for s in scenarios)
        on_start(SweepStart(name, created, before.complete, budget, spec.display, run_dir, names))
    progress = _Progress(budget, on_progress)
    handler = _interrupt_handler()
    t0 = time.monotonic()
    workers: list[WorkerReport] = []
    interrupted = False
    try:
        if cfg.workers == 1:
            rep = run_worker(cfg, spec, name, 0, progress.update, storage=storage)
            workers = [replace(rep, exit=0)]
        else:
            workers = run_processes(cfg, spec, name, lambda: progress.update(study))
    except KeyboardInterrupt:  # the files are written for what the study holds, then
        interrupted = True  # Ctrl-C is acted on again
        if handler is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
    finally:
        elapsed = time.monotonic() - t0
        progress.update(study, final=True)
    try:
        return _finish(cfg, study, spec, scenarios, run_dir, reference, created, elapsed,
                       workers, sum(before), interrupted)  # fmt: skip
    finally:
        if interrupted and handler is not None:
            signal.signal(signal.SIGINT, handler)


def _default_study(stem: str, runs_dir: str) -> str:
    """A new study's name: ``STEM-YYYYmmdd-HHMMSS`` (``-1``, ``-2`` … if taken), the stem
    reduced to letters, digits and ``._-``.

    Parameters
    ----------
    stem : str
        Its first part (``vfgym sweep``: the config file's stem).
    runs_dir : str
        The root of the run folders.

    Returns
    -------
    str
        A name no run folder under ``RUNS_DIR/sweep/`` has.
    """
    stem = "".join(c if c.isalnum() or c in "._-" else "-" for c in stem) or "sweep"
    base = f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    name, i = base, 1
    while (Path(runs_dir) / "sweep" / name).exists():
        name, i = f"{base}-{i}", i + 1
    return name


def _warm_up(cfg: SweepConfig, scenarios: list[Scenario]) -> threading.Thread:
    """Load the compiled kernel on a thread of its own while the study is opened: numba's
    cache and the storage's first opening (its imports, its tables) each take a good
    part of a second, and the first releases the GIL (the worker's own first call then
    finds the kernel loaded)."""

    def load() -> None:
        try:
            evaluate(PAPER_SETTINGS, scenarios[:1], axis=cfg.axis)
        except Exception:  # (the worker's own first call raises it)
            return

    thread = threading.Thread(target=load, name="vfgym-warm-up", daemon=True)
    thread.start()
    return thread


PROGRESS_S = 1.0
"""Seconds between two reads of the study for the progress bar (each is a few storage
queries, beside the trials' own)."""


class _Progress:
    """Tells ``tell`` how far the study is, at most once a second (each read is the
    study's: a storage query a trial would otherwise add), and once at the end."""

    def __init__(self, budget: int, tell: Callable[[SweepProgress], object] | None) -> None:
        self.budget, self.tell = budget, tell
        self.at = 0.0

    def update(self, study: Study, final: bool = False) -> None:
        if self.tell is None or (not final and time.monotonic() - self.at < PROGRESS_S):
            return
        self.at = time.monotonic()
        trials = study.get_trials(deepcopy=False)  # (read once)
        complete = sum(t.state.name == "COMPLETE" for t in trials)
        best = best_of(trials)
        res = None if best is None else stored_result(best)
        cost, feasible = (None, False) if res is None else (res.cost, res.feasible)
        self.tell(SweepProgress(complete, self.budget, cost, feasible, final))


def _interrupt_handler() -> Any:
    """Ctrl-C's handler as the sweep starts, put back after an interrupted sweep has
    written its files (Ctrl-C is ignored meanwhile); None off the main thread, where the
    handler cannot be changed."""
    if threading.current_thread() is not threading.main_thread():
        return None
    handler = signal.getsignal(signal.SIGINT)
    return signal.default_int_handler if handler is None else handler


def _check_same_storage(run_dir: Path, display: str) -> None:
    """A run folder's study continues only in the storage it lives in: another storage
    would start a second study beside it without a word."""
    conf = run_dir / "config.yaml"
    if not conf.is_file():
        return
    old = read_yaml(conf)
    old = old.get("storage") if isinstance(old, dict) else None
    if not isinstance(old, str):
        return

    def kind(s: str) -> str | None:  # a file may have moved with its folder: same kind
        if s.startswith("sqlite:"):
            return "sqlite"
        if s.endswith(".log"):
            return "journal"
        return s if s.startswith("postgresql") else None

    if kind(old) is not None and kind(old) != kind(display):
        raise ValueError(
            f"--storage={display!r} is not allowed for run folder {run_dir}: its study "
            f"lives in {old}; continue it there (leave --storage out, or give the same), "
            "or give another --study"
        )


def _check_storage_file(text: str, spec: StorageSpec) -> None:
    """A storage file named by the user (sqlite:///FILE, journal:FILE) must go in an
    existing folder: a typo must not make folders silently. The defaults ``sqlite`` and
    ``journal`` live in the run folder, which the sweep makes."""
    if spec.path is None or str(text).strip() in ("sqlite", "journal"):
        return
    check_output_path("storage", spec.path, shown=text)  # a missing folder, a file in the way


def _open_study(
    cfg: SweepConfig, spec: StorageSpec, name: str, run_dir: Path, scenarios: list[Scenario]
) -> tuple[BaseStorage, Study, bool]:
    """Open the storage and create or load the study; a run folder made here is removed
    again if that fails (a refused sweep leaves nothing behind)."""
    storage = None
    if spec.kind == "postgresql":  # reach the server before making a run folder
        storage = open_storage(spec, cfg.heartbeat, cfg.grace)
    made = not run_dir.exists()
    run_dir.mkdir(parents=True, exist_ok=True)
    try:
        if storage is None:
            storage = open_storage(spec, cfg.heartbeat, cfg.grace)
        try:
            study, created = create_or_load(storage, name, cfg, scenarios)
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:  # a file, not a journal
            raise ValueError(f"storage={spec.display!r} cannot be opened: {exc}") from None
    except BaseException:
        if made:
            shutil.rmtree(run_dir, ignore_errors=True)
        raise
    return storage, study, created


def _record(
    run_dir: Path, cfg: SweepConfig, name: str, spec: StorageSpec, argv: Sequence[str] | None
) -> None:
    """config.yaml (resolved, password masked), axis.yaml (the axis tuned on) and
    command.txt (every invocation that opened the study: a refused one is not recorded)."""
    conf = cfg.to_dict() | {"study": name, "storage": spec.display}
    write_yaml(run_dir / "config.yaml", {"command": "sweep", **conf})
    write_axis(cfg.axis, run_dir / AXIS_FILE)
    words = list(argv) if argv is not None else cfg.command_words("sweep")
    line = "vfgym " + " ".join(shlex.quote(mask_url(a)) for a in words)
    path = run_dir / "command.txt"
    old = path.read_text(encoding="utf-8") if path.exists() else ""
    write_text(path, old + line + "\n")


def _finish(cfg: SweepConfig, study: Study, spec: StorageSpec, scenarios: list[Scenario],
            run_dir: Path, reference: FoundReference | None, created: bool, elapsed: float,
            workers: list[WorkerReport], made: int, interrupted: bool) -> SweepResult:  # fmt: skip
    """The run's files: trials.csv, best.yaml, the plots, summary.yaml and report.txt;
    ``made``: the study's trials before this run."""
    write_trials_csv(study, run_dir / "trials.csv")
    counts = TrialCounts.of(study)
    budget = trial_budget(cfg)
    # A dead worker's trial, or one interrupted, is failed and enqueued again (Optuna's
    # retry names the trial it repeats): the study says which, whichever worker did it.
    retried = sorted(t.system_attrs[RETRY] for t in study.get_trials(deepcopy=False)[made:]
                     if RETRY in t.system_attrs)  # fmt: skip
    best = best_trial(study)
    record = comparison = verdict = plots = None
    if best is not None:
        settings = trial_settings(best)
        comparison = against_paper(settings, scenarios, "tuned", cfg.axis)
        paper = paper_cost(cfg, scenarios)  # as the sweep scores a setting
        record = best_record(study, best, cfg, spec, scenarios, paper, reference)
        write_yaml(run_dir / "best.yaml", record.as_dict())
        if cfg.plots and not interrupted:
            plots = write_plots(study, run_dir, str(cfg.objective))
        if not interrupted:
            verdict = axis_verdict(settings, cfg.axis, tuned_on=scenarios)
    stops = {w.stopped for w in workers}
    result = SweepResult(
        cfg, study, run_dir, spec, created, counts, budget, elapsed, tuple(workers),
        tuple(retried), record, comparison, verdict, plots, interrupted,
        unfinished=not interrupted and counts.complete < budget and "timeout" not in stops,
    )  # fmt: skip
    write_text(run_dir / "report.txt", result.text() + "\n")
    write_yaml(run_dir / "summary.yaml", result.as_dict())
    return result
