"""The scenario card (``/scenarios/<run_id>/<seq_id>/<edit_id>``): one edit of a run, everything the store knows
of it, each part in its own section so a missing or corrupt file shows its message where it belongs.

    card = read_scenario(store, "mine-0001", "synth-000000", "1f0d7bcaba279490")

Parts: the prompt and parsed commands (``command.json``, else the last program of its attempts), the attempts
that led here (its rows of the run's ``edits`` table, with the judge's reasons), the judge's verdict, the
before/after frames of every camera (after: the edit's ``renders/<camera>/<frame>.exr``; before: the log's
``images/<camera>/<frame>.exr``; by artifact id, EXR served as PNG), the stored BEV still, the motion
(``tasks.dashboard.scenario_motion``), the validation (``validation.json``) and the exported datasets holding it
(the store's dataset listing and each dataset's manifest).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from simsplat_core.editing.commands import EditProgram, program_from_json
from simsplat_core.eval.mining_funnel import failure_classes, stage_reached
from simsplat_core.mining.attempts import judge_reasons_of
from storage.artifact_ids import artifact_id
from storage.datasets import DatasetFolder, list_datasets
from storage.edits import edit_dir, read_edit_manifest, read_edit_program, read_edit_records, validation_from_json
from storage.logs import log_dir
from storage.store import ArtifactStore, join_relpath
from storage.uris import split_name
from tasks.dashboard.mining import edit_rows
from tasks.dashboard.scenario_motion import ScenarioMotion, read_motion
from tasks.dashboard.sections import Section, section
from tasks.rerun_export import rerun_available


@dataclass(frozen=True)
class AttemptView:
    """One attempt of the scenario (a row of the run's edits table).

    Attributes:
        status: the table's (``succeeded`` / ``refused`` / ``failed``); mining_status: the loop's (``""``: a plain
            edit); stage: the furthest funnel stage it passed (``""``: a plain edit); failures: its failure classes.
        judge_reasons: the judge's reasons (``()``: not judged, or a table written before they were kept).
    """

    attempt: int
    status: str
    mining_status: str
    stage: str
    failure_reason: str
    failures: tuple[str, ...]
    follows_prompt: bool | None
    plausibility: int | None
    judge_reasons: tuple[str, ...]
    adjustment: str


@dataclass(frozen=True)
class Verdict:
    """The judge's verdict on the attempt shown (the accepted one, else the last judged one)."""

    attempt: int
    follows_prompt: bool
    plausibility: int
    reasons: tuple[str, ...]
    accepted: bool


@dataclass(frozen=True)
class CommandView:
    """One parsed command: its op, what it targets, and its set fields (``"behaviour.reverse": "true"``)."""

    op: str
    target: str
    fields: dict[str, str]


@dataclass(frozen=True)
class ProgramView:
    """The parsed commands; source: where they were read (``command.json`` or the edits table)."""

    prompt: str
    commands: list[CommandView]
    source: str
    json: str


@dataclass(frozen=True)
class FramePair:
    """One camera at one frame: artifact ids of the log's image (``before``) and the edit's render (``after``);
    ``""`` where the store has none."""

    frame: int
    before: str
    after: str


@dataclass(frozen=True)
class CameraFrames:
    """Every frame of one camera, in frame order."""

    camera: str
    frames: list[FramePair]


@dataclass(frozen=True)
class Pictures:
    """The stored pictures: bev.png and before_after.png ids (``""``: absent), and the frames per camera."""

    bev: str
    before_after: str
    frames: list[int]
    cameras: list[CameraFrames]


@dataclass(frozen=True)
class DatasetEntry:
    """A dataset holding the scenario: its name, where it is, and its scenario ids with their splits; or a listed
    dataset whose manifest could not be read (``error`` says why; then it is not known whether it holds it)."""

    name: str
    uri: str
    scenarios: dict[str, str]
    error: str = ""


@dataclass(frozen=True)
class ScenarioView:
    """The card (module docstring). ``stored``: the edit directory is complete (its ``_SUCCESS.json``);
    ``recording``: a Rerun recording of it can be made (stored, and the optional rerun-sdk installed)."""

    run_id: str
    seq_id: str
    edit_id: str
    prompt: str
    category: str
    status: str
    stored: bool
    attempts: Section[list[AttemptView]]
    verdict: Section[Verdict | None]
    program: Section[ProgramView]
    pictures: Section[Pictures]
    motion: Section[ScenarioMotion]
    validation: Section[dict[str, Any]]
    exports: Section[list[DatasetEntry]]
    recording: bool = False


def _attempt(row: Mapping[str, Any]) -> AttemptView:
    mined = bool(row.get("mining_status"))
    return AttemptView(
        attempt=int(row["attempt"]), status=str(row["status"]), mining_status=str(row.get("mining_status") or ""),
        stage=stage_reached(row) if mined else "", failure_reason=str(row["failure_reason"] or ""),
        failures=failure_classes(str(row["failure_reason"] or "")), follows_prompt=row.get("follows_prompt"),
        plausibility=row.get("plausibility"), judge_reasons=judge_reasons_of(row.get("judge_reasons")),
        adjustment=str(row.get("adjustment") or ""))


def _verdict(attempts: list[AttemptView]) -> Verdict | None:
    judged = [a for a in attempts if a.follows_prompt is not None and a.plausibility is not None]
    accepted = [a for a in judged if a.mining_status == "accepted"]
    if not judged:
        return None
    shown = (accepted or judged)[-1]
    return Verdict(shown.attempt, bool(shown.follows_prompt), int(shown.plausibility or 0), shown.judge_reasons,
                   shown.mining_status == "accepted")


def _flat(prefix: str, value: Any) -> dict[str, str]:
    if isinstance(value, dict):
        return {k: v for name, sub in value.items() for k, v in _flat(f"{prefix}.{name}" if prefix else name,
                                                                     sub).items()}
    return {prefix: json.dumps(value) if not isinstance(value, str) else value}


def _command_views(program: EditProgram) -> list[CommandView]:
    out = []
    for command in program.commands:
        data = command.model_dump(mode="json", exclude_defaults=True, exclude_none=True)
        target = data.pop("target", {})
        data.pop("op", None)
        out.append(CommandView(command.op, str(target.get("description", "")) if target else "", _flat("", data)))
    return out


def _program(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str, rows: list[dict[str, Any]]
             ) -> ProgramView:
    rel = join_relpath(edit_dir(run_id, seq_id, edit_id), "command.json")
    if store.exists(rel):
        program, source = read_edit_program(store, run_id, seq_id, edit_id), "command.json"
    else:
        text = next((r["command_json"] for r in reversed(rows) if r["command_json"]), "")
        if not text:
            raise FileNotFoundError(f"{store.uri(rel)}: absent, and no attempt of {edit_id} made a program "
                                    "(the prompt was refused before it became commands)")
        program, source = program_from_json(text, source=f"edits table, {edit_id}"), "edits table"
    return ProgramView(program.prompt, _command_views(program), source, program.model_dump_json(indent=2))


def _pictures(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> Pictures:
    rel = edit_dir(run_id, seq_id, edit_id)
    renders = [p for p in store.walk(join_relpath(rel, "renders")) if p.endswith(".exr")]
    images = set(store.walk(join_relpath(log_dir(seq_id), "images")))
    by_camera: dict[str, list[int]] = {}
    for path in renders:
        camera, _, name = path.rpartition("/")
        if name[:-4].isdigit():
            by_camera.setdefault(camera, []).append(int(name[:-4]))
    cameras = []
    for camera, frames in sorted(by_camera.items()):
        pairs = []
        for frame in sorted(frames):
            name = f"{camera}/{frame:06d}.exr"
            before = artifact_id(join_relpath(log_dir(seq_id), "images", name)) if name in images else ""
            pairs.append(FramePair(frame, before, artifact_id(join_relpath(rel, "renders", name))))
        cameras.append(CameraFrames(camera, pairs))
    frames = sorted({p.frame for c in cameras for p in c.frames})

    def still(name: str) -> str:
        return artifact_id(join_relpath(rel, name)) if store.exists(join_relpath(rel, name)) else ""

    return Pictures(still("bev.png"), still("before_after.png"), frames, cameras)


def _validation(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> dict[str, Any]:
    rel = join_relpath(edit_dir(run_id, seq_id, edit_id), "validation.json")
    if not store.exists(rel):
        raise FileNotFoundError(f"{store.uri(rel)}: no validation.json (the edit was not stored, or is incomplete)")
    return validation_from_json(store, run_id, seq_id, edit_id)


def _exports(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> list[DatasetEntry]:
    prefix = f"{run_id}/{seq_id}/{edit_id}/"
    out = []
    for listing in list_datasets(store):
        uri = str(listing.get("uri", ""))
        parent, name = split_name(uri)
        label = str(listing.get("name", name))
        read = section(f"dataset {label}", lambda parent=parent, name=name: DatasetFolder(parent, name).read_manifest()
                       if parent and name else None)  # type: ignore[misc]
        if not read.ok or read.value is None:
            out.append(DatasetEntry(label, uri, {}, read.error or f"no manifest at {uri!r}"))
            continue
        held = {sid: str(entry.get("split", "")) for sid, entry in read.value.get("scenarios", {}).items()
                if str(entry.get("input", "")).startswith(prefix)}
        if held:
            out.append(DatasetEntry(label, uri, held))
    return out


def read_scenario(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> ScenarioView | None:
    """The card of one edit (module docstring); ``None`` when the run's table has no row of it and the store no
    directory for it."""
    records = section("attempts", lambda: edit_rows([r for r in read_edit_records(store, run_id)
                                                     if r.seq_id == seq_id and r.edit_id == edit_id]))
    rows = records.value or []
    manifest = read_edit_manifest(store, run_id, seq_id, edit_id)
    if records.ok and not rows and manifest is None and not store.is_dir(edit_dir(run_id, seq_id, edit_id)):
        return None
    attempts: Section[list[AttemptView]] = (Section("attempts", value=[_attempt(r) for r in rows]) if records.ok
                                            else Section("attempts", error=records.error))
    last = rows[-1] if rows else {}
    accepted = any(r.get("mining_status") == "accepted" for r in rows)
    status = "accepted" if accepted else str(last.get("mining_status") or last.get("status") or "unknown")
    return ScenarioView(
        run_id=run_id, seq_id=seq_id, edit_id=edit_id, prompt=str(last.get("prompt", "")),
        category=str(next((r["category"] for r in reversed(rows) if r.get("category")), "")), status=status,
        stored=manifest is not None, attempts=attempts,
        verdict=section("verdict", lambda: _verdict(attempts.value or [])),
        program=section("commands", lambda: _program(store, run_id, seq_id, edit_id, rows)),
        pictures=section("frames", lambda: _pictures(store, run_id, seq_id, edit_id)),
        motion=section("motion", lambda: read_motion(store, run_id, seq_id, edit_id)),
        validation=section("validation", lambda: _validation(store, run_id, seq_id, edit_id)),
        exports=section("export status", lambda: _exports(store, run_id, seq_id, edit_id)),
        recording=manifest is not None and rerun_available())


__all__ = ["AttemptView", "CameraFrames", "CommandView", "DatasetEntry", "FramePair", "Pictures", "ProgramView",
           "ScenarioView", "Verdict", "read_scenario"]
