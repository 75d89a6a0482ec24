"""A flow run's record: what the run is, how far it got, and each sequence's stages, written while it runs.

    runs/<run_id>/run.json                              the run (``RunRecord``), rewritten as it goes
    runs/<run_id>/stages/<seq_id>/<stage>-<status>.json one event of one sequence's stage (``StageRecord``)

Every file is small and written atomically, and a stage event is a file of its own (never an append to a shared
file), so the driver, its threads and Ray workers can record side by side and a reader never sees half a file
(an interrupted writer leaves at most a ``.tmp-`` file, which readers skip). The newest event of a
``(sequence, stage)`` is its state. ``read_stage_matrix`` aggregates the events into a sequence x stage matrix; a
garbled event file is reported in the matrix's ``problems`` (naming the file) and left out, never fatal.

A running run rewrites its ``run.json`` every ``HEARTBEAT_S`` seconds (``heartbeat_at``). A run whose process died
(SIGKILL, the OOM killer, a lost machine) cannot write ``failed``, so its file says ``running`` for ever: a reader
asks ``RunRecord.observed_status`` instead, which says ``interrupted`` once no heartbeat came for ``STALE_AFTER_S``.

Times are ISO 8601 UTC strings with microseconds; durations are seconds.
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from storage.errors import CorruptArtifactError
from storage.runs import RUNS_DIR, run_dir
from storage.store import TMP_TAG, ArtifactStore, join_relpath

RUN_RECORD = "run.json"
STAGES_DIR = "stages"
RECORD_VERSION = 1

#: The stages of the pipeline, in the order a sequence goes through them (columns of the matrix).
PIPELINE_STAGES: tuple[str, ...] = ("ingest", "reconstruct", "align", "mine", "evaluate", "export")
RUN_STATUSES: tuple[str, ...] = ("running", "completed", "failed")
#: What a reader calls a ``running`` record whose heartbeat stopped (never written to a file).
INTERRUPTED = "interrupted"
#: Seconds between two heartbeats of a running run, s.
HEARTBEAT_S = 30.0
#: Seconds without a heartbeat after which a running run reads as ``interrupted``, s.
STALE_AFTER_S = 3 * HEARTBEAT_S
STAGE_STATUSES: tuple[str, ...] = ("queued", "running", "completed", "skipped", "failed")
#: Among events recorded at the same instant, the later status in this order wins.
_STATUS_RANK = {"queued": 0, "running": 1, "completed": 2, "skipped": 2, "failed": 2}
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")


def utc_now() -> str:
    """The current UTC time as ISO 8601 with microseconds (``2026-11-27T16:58:18.912979+00:00``)."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds")


def parse_time(text: str | None) -> datetime.datetime | None:
    """An ISO 8601 time of a record (``None`` stays ``None``); naive times are taken as UTC.

    Raises:
        ValueError: ``text`` is not an ISO 8601 time.
    """
    if text is None:
        return None
    when = datetime.datetime.fromisoformat(text)
    return when if when.tzinfo else when.replace(tzinfo=datetime.UTC)


def json_safe(value: Any) -> Any:
    """``value`` as strict JSON data (a record's parameters, the dashboard's JSON twins): dataclasses and mappings as
    objects, sequences and numpy arrays as lists, numpy scalars and enums by value, non-finite floats as ``None``,
    anything else (paths) by its ``str``."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: json_safe(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.generic):
        return json_safe(value.item())
    if isinstance(value, enum.Enum):
        return json_safe(value.value)
    if isinstance(value, bool | int | str) or value is None:
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def _check_name(kind: str, name: str) -> str:
    if not _NAME.match(name):
        raise ValueError(f"{kind} {name!r} must be 1-128 characters of letters, digits, '.', '_' or '-'")
    return name


def _choice(kind: str, value: str, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise ValueError(f"{kind} {value!r} is not one of {list(allowed)}")
    return value


@dataclass(frozen=True)
class RunRecord:
    """One flow run (``runs/<run_id>/run.json``).

    Attributes:
        run_id: the run (its folder's name).
        flow: the flow's name (``simsplat-main``).
        status: ``running``, ``completed`` or ``failed``.
        started_at, finished_at: ISO 8601 UTC (``finished_at`` ``None`` while running).
        code_version: ``git describe`` of the code that ran (``tasks.code_version``).
        parameters: the flow's parameters as JSON data.
        counts: what the run produced so far (``logs``, ``scenes``, ``language_scenes``, ``accepted_scenarios``,
            ``exported``).
        error: why a failed run failed (``"<ExceptionType>: <message>"``).
        heartbeat_at: the last time the running run's process rewrote the record (ISO 8601 UTC; ``None``: never).
    """

    run_id: str
    flow: str
    status: str
    started_at: str
    finished_at: str | None = None
    code_version: str = ""
    parameters: Mapping[str, Any] = field(default_factory=dict)
    counts: Mapping[str, int] = field(default_factory=dict)
    error: str = ""
    heartbeat_at: str | None = None

    def __post_init__(self) -> None:
        _check_name("run id", self.run_id)
        _choice("run status", self.status, RUN_STATUSES)
        parse_time(self.started_at)
        parse_time(self.finished_at)
        parse_time(self.heartbeat_at)

    @property
    def last_sign_of_life(self) -> datetime.datetime | None:
        """The newest heartbeat (the start when none was written yet)."""
        return parse_time(self.heartbeat_at or self.started_at)

    def observed_status(self, now: datetime.datetime | None = None) -> str:
        """``status``, except ``interrupted`` for a ``running`` record without a heartbeat for ``STALE_AFTER_S`` at
        ``now`` (default: the current time): its process died without recording the end."""
        last = self.last_sign_of_life
        now = now or datetime.datetime.now(datetime.UTC)
        if self.status == "running" and last is not None and (now - last).total_seconds() > STALE_AFTER_S:
            return INTERRUPTED
        return self.status

    def seconds(self, now: datetime.datetime | None = None) -> float | None:
        """The run's duration so far (to ``now``, default the current time, while it runs; to the last heartbeat
        when it was interrupted), s."""
        start = parse_time(self.started_at)
        now = now or datetime.datetime.now(datetime.UTC)
        end = parse_time(self.finished_at) or (self.last_sign_of_life if self.observed_status(now) == INTERRUPTED
                                               else now)
        return None if start is None or end is None else max(0.0, (end - start).total_seconds())


@dataclass(frozen=True)
class StageRecord:
    """One event of one sequence's stage in a run.

    Attributes:
        seq_id: the sequence; stage: one of ``PIPELINE_STAGES`` (other names are kept as they are).
        status: ``queued``, ``running``, ``completed``, ``skipped`` or ``failed``.
        recorded_at: when the event was written (ISO 8601 UTC; the newest event is the stage's state).
        started_at: when the stage's task started (or was submitted), ``None`` when it never ran.
        seconds: how long the task ran, s (``None`` unless completed or failed).
        retries: attempts beyond the first (the Prefect task run's run count minus one; ``None``: unknown).
        error: the failure message of a failed stage; skip_reason: why a skipped stage was skipped.
        task: the Prefect task (or task run) that did the work.
        note: anything else worth showing ("reused the stored scene", "one task for 2 sequences").
    """

    seq_id: str
    stage: str
    status: str
    recorded_at: str
    started_at: str | None = None
    seconds: float | None = None
    retries: int | None = None
    error: str = ""
    skip_reason: str = ""
    task: str = ""
    note: str = ""

    def __post_init__(self) -> None:
        _check_name("sequence id", self.seq_id)
        _check_name("stage", self.stage)
        _choice("stage status", self.status, STAGE_STATUSES)
        parse_time(self.recorded_at)
        parse_time(self.started_at)
        if self.seconds is not None and not (isinstance(self.seconds, int | float) and self.seconds >= 0):
            raise ValueError(f"seconds must be a non-negative number, got {self.seconds!r}")
        if self.retries is not None and not (isinstance(self.retries, int) and self.retries >= 0):
            raise ValueError(f"retries must be a non-negative integer, got {self.retries!r}")

    @property
    def order(self) -> tuple[datetime.datetime, int]:
        """Sort key of events: newest last; at the same instant a later status last."""
        recorded = parse_time(self.recorded_at)
        assert recorded is not None
        return recorded, _STATUS_RANK[self.status]


@dataclass(frozen=True)
class StageMatrix:
    """A run's sequence x stage matrix: the newest event of every recorded ``(sequence, stage)``.

    Attributes:
        seq_ids: the rows (sorted); stages: the columns (``PIPELINE_STAGES`` first, then any other recorded).
        cells: ``(seq_id, stage) -> StageRecord``; a pair without a record was never reached.
        problems: one message per stage file that could not be read (naming it); those files are left out.
    """

    seq_ids: tuple[str, ...] = ()
    stages: tuple[str, ...] = PIPELINE_STAGES
    cells: Mapping[tuple[str, str], StageRecord] = field(default_factory=dict)
    problems: tuple[str, ...] = ()

    def cell(self, seq_id: str, stage: str) -> StageRecord | None:
        return self.cells.get((seq_id, stage))


def run_record_relpath(run_id: str) -> str:
    """``runs/<run_id>/run.json``."""
    return join_relpath(run_dir(run_id), RUN_RECORD)


def stage_record_relpath(run_id: str, seq_id: str, stage: str, status: str) -> str:
    """``runs/<run_id>/stages/<seq_id>/<stage>-<status>.json``."""
    return join_relpath(run_dir(run_id), STAGES_DIR, _check_name("sequence id", seq_id),
                        f"{_check_name('stage', stage)}-{_choice('stage status', status, STAGE_STATUSES)}.json")


def write_run_record(store: ArtifactStore, record: RunRecord) -> None:
    """Write (or replace) ``record`` atomically."""
    store.write_json(run_record_relpath(record.run_id), {"record_version": RECORD_VERSION,
                                                         **json_safe(record)})


def write_stage_record(store: ArtifactStore, run_id: str, record: StageRecord) -> None:
    """Write one stage event of run ``run_id`` atomically, as a file of its own."""
    relpath = stage_record_relpath(run_id, record.seq_id, record.stage, record.status)
    store.write_json(relpath, {"record_version": RECORD_VERSION, **json_safe(record)})


def _record_from(cls: type, data: Any, source: str) -> Any:
    """``cls(**data)`` from a record file's JSON; ``CorruptArtifactError`` naming the file and the field."""
    if not isinstance(data, dict):
        raise CorruptArtifactError(f"{source}: a record must be a JSON object, got {type(data).__name__}")
    names = {f.name for f in dataclasses.fields(cls)}
    missing = sorted(f.name for f in dataclasses.fields(cls)
                     if f.name not in data and f.default is dataclasses.MISSING
                     and f.default_factory is dataclasses.MISSING)
    if missing:
        raise CorruptArtifactError(f"{source}: missing field(s) {missing}")
    try:
        return cls(**{k: v for k, v in data.items() if k in names})
    except (TypeError, ValueError) as exc:
        raise CorruptArtifactError(f"{source}: {exc}") from exc


def read_run_record(store: ArtifactStore, run_id: str) -> RunRecord | None:
    """Run ``run_id``'s record, ``None`` when it has none (an evaluation-only run folder).

    Raises:
        CorruptArtifactError: the file is not valid JSON or a field is missing or wrong (naming both).
    """
    relpath = run_record_relpath(run_id)
    if not store.exists(relpath):
        return None
    record: RunRecord = _record_from(RunRecord, store.read_json(relpath), store.uri(relpath))
    if record.run_id != run_id:
        raise CorruptArtifactError(f"{store.uri(relpath)}: run_id {record.run_id!r} is not its folder's {run_id!r}")
    return record


def read_stage_record(store: ArtifactStore, run_id: str, seq_id: str, stage: str, status: str) -> StageRecord | None:
    """The ``status`` event of ``seq_id``'s ``stage`` in run ``run_id``, ``None`` when not recorded.

    Raises:
        CorruptArtifactError: the file is garbled (naming it).
    """
    relpath = stage_record_relpath(run_id, seq_id, stage, status)
    if not store.exists(relpath):
        return None
    record: StageRecord = _record_from(StageRecord, store.read_json(relpath), store.uri(relpath))
    return record


def _stage_files(store: ArtifactStore, run_id: str) -> list[str]:
    base = join_relpath(run_dir(run_id), STAGES_DIR)
    return [join_relpath(base, seq, name) for seq in store.listdir(base) if not seq.startswith(".")
            for name in store.listdir(join_relpath(base, seq))
            if name.endswith(".json") and TMP_TAG not in name and not name.startswith(".")]


def read_stage_matrix(store: ArtifactStore, run_id: str) -> StageMatrix:
    """Every stage event of run ``run_id`` aggregated into its ``StageMatrix`` (empty when none was recorded).

    A file that is not valid JSON, or not a valid record, or whose folder and name disagree with its fields, is
    named in ``problems`` and left out.
    """
    newest: dict[tuple[str, str], StageRecord] = {}
    problems: list[str] = []
    for relpath in _stage_files(store, run_id):
        try:
            record: StageRecord = _record_from(StageRecord, store.read_json(relpath), store.uri(relpath))
            if relpath != stage_record_relpath(run_id, record.seq_id, record.stage, record.status):
                raise CorruptArtifactError(f"{store.uri(relpath)}: its fields say {record.seq_id}/{record.stage}-"
                                           f"{record.status}, not its file name")
        except (CorruptArtifactError, OSError) as exc:
            problems.append(str(exc))
            continue
        key = (record.seq_id, record.stage)
        if key not in newest or newest[key].order <= record.order:
            newest[key] = record
    extra = sorted({stage for _, stage in newest} - set(PIPELINE_STAGES))
    return StageMatrix(tuple(sorted({seq for seq, _ in newest})), (*PIPELINE_STAGES, *extra), newest,
                       tuple(problems))


def list_run_ids(store: ArtifactStore) -> list[str]:
    """Every run folder of the store (with a run record or only evaluation tables), sorted by name."""
    return [name for name in store.listdir(RUNS_DIR) if _NAME.match(name) and store.is_dir(join_relpath(RUNS_DIR,
                                                                                                         name))]
