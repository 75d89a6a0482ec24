"""What an export takes from the store: the chosen logs or edits, each turned into ``ScenarioSource``s.

``select_inputs`` applies the filters of ``simsplat export`` (``--include accepted | all-edits | logs``, ``--run``,
``--category``, ``--min-plausibility``) to the store's edit runs or logs, with a clear error for an empty store, an
unknown run or category, or a selection that leaves nothing; ``scenario_source`` reads one input (the log without
images, the edit's stored trajectories) into what ``simsplat_core.export.from_log`` windows.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

from simsplat_core.export.from_log import ScenarioSource, edit_source, log_agent_states, log_source
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.types import SceneLog
from storage import ArtifactStore, read_scene_log
from storage.edits import (
    EDITS_DIR,
    EditRecord,
    edit_dir,
    edit_run_ids,
    read_edit_records,
    read_trajectories,
    trajectory_states,
    validation_from_json,
)
from storage.inventory import MissingInputError, require_sequences
from storage.logs import read_log_manifest
from storage.markers import read_marker

logger = logging.getLogger(__name__)

#: ``--include`` choices: accepted mined scenarios, every succeeded edit, the unedited logs.
INCLUDE_CHOICES: tuple[str, ...] = ("accepted", "all-edits", "logs")


@dataclass(frozen=True)
class ExportFilters:
    """Which scenarios of a store an export takes.

    Attributes:
        include: one of :data:`INCLUDE_CHOICES`.
        runs: edit runs to take edits from (default: every run of the store).
        categories: edit categories to keep (``mining.rule_proposals.EDIT_CATEGORIES``; default: all).
        min_plausibility: keep judged scenarios at least this plausible (1-5; default: no bound).
        sequences: logs to export with ``include="logs"`` (default: every log).
    """

    include: str = "accepted"
    runs: tuple[str, ...] = ()
    categories: tuple[str, ...] = ()
    min_plausibility: int | None = None
    sequences: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.include not in INCLUDE_CHOICES:
            raise ValueError(f"--include {self.include!r}: choose one of {list(INCLUDE_CHOICES)}")
        unknown = sorted(set(self.categories) - set(EDIT_CATEGORIES))
        if unknown:
            raise ValueError(f"--category {unknown}: unknown; the edit categories are {list(EDIT_CATEGORIES)}")
        if self.min_plausibility is not None and not 1 <= self.min_plausibility <= 5:
            raise ValueError(f"--min-plausibility {self.min_plausibility}: the judge scores 1 to 5")

    def as_dict(self) -> dict[str, object]:
        return {"include": self.include, "runs": list(self.runs), "categories": list(self.categories),
                "min_plausibility": self.min_plausibility, "sequences": list(self.sequences)}


@dataclass(frozen=True)
class ExportInput:
    """One log or edit to export.

    Attributes:
        seq_id: the log.
        key: the content key of what is exported (the log's, or the edit's marker key).
        record: the edit's row of its run's ``edits`` table; ``None`` for an unedited log.
    """

    seq_id: str
    key: str
    record: EditRecord | None = field(default=None, hash=False)

    @property
    def input_id(self) -> str:
        """``<seq>`` for a log, ``<run>/<seq>/<edit>/<attempt>`` for an edit."""
        r = self.record
        return self.seq_id if r is None else f"{r.run_id}/{r.seq_id}/{r.edit_id}/{r.attempt}"


def _keep(record: EditRecord, filters: ExportFilters) -> bool:
    if record.status != "succeeded":
        return False
    if filters.include == "accepted" and not record.export:
        return False
    if filters.categories and record.mining.get("category") not in filters.categories:
        return False
    plausibility = record.mining.get("plausibility")
    return filters.min_plausibility is None or (plausibility is not None and plausibility >= filters.min_plausibility)


def _edit_inputs(store: ArtifactStore, filters: ExportFilters) -> list[ExportInput]:
    runs = edit_run_ids(store)
    unknown = sorted(set(filters.runs) - set(runs))
    if unknown:
        raise MissingInputError(f"--run {unknown}: no such edit run in {store.uri(EDITS_DIR)}; runs: {runs}")
    chosen = list(filters.runs) or runs
    if not chosen:
        raise MissingInputError(f"no edit run in {store.uri(EDITS_DIR)}: mine scenarios first (`simsplat mine "
                                f"--store {store.root}` or `simsplat run --mine K`), or export the logs with "
                                "--include logs")
    out: list[ExportInput] = []
    seen: set[tuple[str, str, str]] = set()
    for run in chosen:
        for record in read_edit_records(store, run):
            where = (run, record.seq_id, record.edit_id)
            if where in seen or not _keep(record, filters):
                continue
            marker = read_marker(store, edit_dir(run, record.seq_id, record.edit_id))
            if marker is None:
                logger.warning("edit %s/%s/%s has no complete edit directory; left out", *where)
                continue
            seen.add(where)
            out.append(ExportInput(record.seq_id, str(marker.get("key", "")), record))
    if not out:
        what = "accepted scenario" if filters.include == "accepted" else "succeeded edit"
        raise MissingInputError(f"no {what} in run(s) {chosen} of {store.uri(EDITS_DIR)} passes the filters "
                                f"{filters.as_dict()}")
    return out


def select_inputs(store: ArtifactStore, filters: ExportFilters) -> list[ExportInput]:
    """The logs or edits ``filters`` choose (module docstring).

    Raises:
        MissingInputError: the store holds no log, no edit run (for edits), an unknown run, or nothing passes.
    """
    require_sequences(store)  # an empty store: say how to add logs
    if filters.include != "logs":
        return _edit_inputs(store, filters)
    seq_ids = require_sequences(store, list(filters.sequences) or None)
    return [ExportInput(s, str((read_log_manifest(store, s) or {}).get("key", ""))) for s in seq_ids]


class LogCache:
    """Logs (without images) and their unedited agent states, read once per sequence."""

    def __init__(self, store: ArtifactStore) -> None:
        self.store = store
        self._logs: dict[str, tuple[SceneLog, AgentStates]] = {}

    def get(self, seq_id: str) -> tuple[SceneLog, AgentStates]:
        if seq_id not in self._logs:
            log = read_scene_log(self.store, seq_id, load_images=False)
            self._logs = {seq_id: (log, log_agent_states(log))}  # one sequence at a time: inputs come grouped
        return self._logs[seq_id]


def _edit_metadata(store: ArtifactStore, record: EditRecord) -> dict[str, str]:
    mining = record.mining
    validation = validation_from_json(store, record.run_id, record.seq_id, record.edit_id)

    def text(value: object) -> str:
        return "" if value is None else str(value).lower() if isinstance(value, bool) else str(value)

    return {
        "run_id": record.run_id, "edit_id": record.edit_id, "attempt": str(record.attempt), "prompt": record.prompt,
        "commands_json": record.command_json, "category": text(mining.get("category")),
        "mining_status": text(mining.get("mining_status")), "follows_prompt": text(mining.get("follows_prompt")),
        "plausibility": text(mining.get("plausibility")), "validation_json": json.dumps(validation, sort_keys=True),
        "edit_dir": store.uri(edit_dir(record.run_id, record.seq_id, record.edit_id)),
    }


def scenario_source(store: ArtifactStore, logs: LogCache, item: ExportInput) -> ScenarioSource:
    """The scenario source of one input: the unedited log, or the log with the edit's stored trajectories."""
    log, log_states = logs.get(item.seq_id)
    record = item.record
    if record is None:
        return log_source(log)
    table = read_trajectories(store, record.run_id, record.seq_id, record.edit_id)
    states = trajectory_states(table, log_states)
    key = f"{record.seq_id}-{record.edit_id[:12]}-a{record.attempt}"
    return edit_source(log, states, key, _edit_metadata(store, record))


def group_by_sequence(inputs: Sequence[ExportInput]) -> list[ExportInput]:
    """``inputs`` ordered by sequence (stable within one), so each log is read once."""
    order = {s: k for k, s in enumerate(dict.fromkeys(i.seq_id for i in inputs))}
    return sorted(inputs, key=lambda i: order[i.seq_id])
