"""Edit one stored scene from a prompt (or a command file) and store the edit (what ``simsplat edit`` runs).

Thin: load the stored sequence's edit context (``tasks.stored_edits.load_edit_context``), call
``simsplat_core.editing`` (parse, ground, apply, validate), and write the edit (``tasks.stored_edits.write_edit``):
``edits/<run_id>/<seq_id>/<edit_id>/`` plus one row of the run's ``edits`` table. A refused or failed edit writes
only its failure record. The same edit of the same inputs (``tasks.stored_edits.edit_key``) is found again and not
re-rendered.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import dataclass, field

import pydantic

from simsplat_core.editing.apply import apply_edit
from simsplat_core.editing.commands import EditProgram, program_from_json
from simsplat_core.editing.options import DEFAULT_OPTIONS, EditorOptions
from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.editing.result import EditedScene, EditRefused
from simsplat_core.motion.predictor import MotionPredictor
from storage import ArtifactStore
from storage.edits import EditRecord, command_json, edit_dir, read_edit_manifest, record_failure
from storage.runs import new_run_id
from tasks.stored_edits import LoadedEdit, Progress, edit_key, load_edit_context, write_edit

logger = logging.getLogger(__name__)

#: Run id of edits made without ``--run-id``.
DEFAULT_RUN_ID = "manual"


@dataclass(frozen=True, eq=False)
class EditRun:
    """What one edit attempt did.

    Attributes:
        status: ``"succeeded"``, ``"refused"`` or ``"failed"``.
        run_id, seq_id, edit_id, edit_uri: where it is stored (``edit_uri`` is ``""`` when nothing but the
            failure record was written).
        prompt, program: the words and the commands (``None`` when the prompt did not parse / the JSON was bad).
        edited: the edited scene (``None`` unless it succeeded).
        reason, message: why it was refused / failed (``""`` otherwise).
        seconds: per stage (``load``, ``parse``, ``apply``, ``render``, ``write``, ``total``).
        bytes: bytes per part of the stored edit (``total`` included; empty when nothing was written).
        skipped: the same edit was already stored (nothing re-rendered).
    """

    status: str
    run_id: str
    seq_id: str
    edit_id: str
    edit_uri: str
    prompt: str
    program: EditProgram | None
    edited: EditedScene | None
    reason: str = ""
    message: str = ""
    seconds: dict[str, float] = field(default_factory=dict)
    bytes: dict[str, int] = field(default_factory=dict)
    skipped: bool = False


def _failure(store: ArtifactStore, loaded: LoadedEdit, run_id: str, edit_id: str, prompt: str,
             program: EditProgram | None, status: str, reason: str, message: str, seconds: dict[str, float]
             ) -> EditRun:
    record = EditRecord(run_id=run_id, seq_id=loaded.ctx.log.seq_id, edit_id=edit_id, prompt=prompt,
                        command_json=command_json(program), status=status, failure_reason=f"{reason}: {message}")
    record_failure(store, record, program)
    logger.info("%s %s: %s (%s)", loaded.ctx.log.seq_id, status, message, reason)
    return EditRun(status, run_id, loaded.ctx.log.seq_id, edit_id, "", prompt, program, None, reason, message,
                   seconds)


def run_edit(store_root: str, seq_id: str, prompt: str = "", *, commands_json: str | None = None,
             commands_source: str = "command JSON", run_id: str | None = None,
             options: EditorOptions = DEFAULT_OPTIONS, loaded: LoadedEdit | None = None,
             predictor: MotionPredictor | None = None, progress: Progress | None = None) -> EditRun:
    """Edit ``seq_id`` by ``prompt`` (or by the commands in ``commands_json``) and store the result.

    ``loaded``: the sequence's edit context when the caller loaded it (``load_edit_context``; its store is used,
    the store is not opened again), else it is loaded here with ``predictor`` driving refinement.

    Returns an :class:`EditRun` for every outcome the user caused (refusals, bad command JSON); only
    unexpected errors raise, after their failure record is written.

    Raises:
        FileNotFoundError: the store lacks the sequence's log or language scene (naming what to run).
    """
    store = loaded.store if loaded is not None else ArtifactStore(store_root)
    run_id = run_id or DEFAULT_RUN_ID
    seconds: dict[str, float] = {}
    loaded = loaded or load_edit_context(store, seq_id, predictor=predictor)
    seconds["load"] = loaded.seconds
    started = time.perf_counter() - loaded.seconds  # the totals include loading
    ctx = loaded.ctx

    t = time.perf_counter()
    program: EditProgram | None = None
    try:
        if commands_json is not None:
            program = program_from_json(commands_json, source=commands_source)
            if prompt and not program.prompt:
                program = program.model_copy(update={"prompt": prompt})
            prompt = prompt or program.prompt
        else:
            program = parse_prompt(prompt, encoder=ctx.engine.text_encoder)
            program = program if program.prompt else program.model_copy(update={"prompt": prompt})
    except (pydantic.ValidationError, json.JSONDecodeError) as exc:
        seconds["parse"] = time.perf_counter() - t
        edit_id = edit_key(loaded, prompt, None, options, commands_json or "")[:16]
        return _failure(store, loaded, run_id, edit_id, prompt, None, "refused", "invalid_command",
                        schema_error_message(exc, commands_source), seconds)
    except EditRefused as exc:
        seconds["parse"] = time.perf_counter() - t
        edit_id = edit_key(loaded, prompt, None, options)[:16]
        return _failure(store, loaded, run_id, edit_id, prompt, None, "refused", exc.reason, str(exc), seconds)
    seconds["parse"] = time.perf_counter() - t
    key = edit_key(loaded, prompt, program, options)
    edit_id = key[:16]

    t = time.perf_counter()
    try:
        edited = apply_edit(ctx, program, options)
    except EditRefused as exc:
        seconds["apply"] = time.perf_counter() - t
        message = str(exc) if exc.command_index is None else f"command {exc.command_index + 1}: {exc}"
        return _failure(store, loaded, run_id, edit_id, prompt, program, "refused", exc.reason, message, seconds)
    seconds["apply"] = time.perf_counter() - t

    rel = edit_dir(run_id, seq_id, edit_id)
    manifest = read_edit_manifest(store, run_id, seq_id, edit_id)
    if manifest is not None and manifest.get("key") == key:
        seconds["total"] = time.perf_counter() - started
        logger.info("%s: edit %s already stored, skipping", seq_id, edit_id)
        return EditRun("succeeded", run_id, seq_id, edit_id, store.uri(rel), prompt, program, edited, seconds=seconds,
                       bytes=dict(manifest.get("bytes", {})), skipped=True)
    record = EditRecord(run_id=run_id, seq_id=seq_id, edit_id=edit_id, prompt=prompt,
                        command_json=command_json(program), status="succeeded")
    try:
        sizes = write_edit(store, record, key, loaded, program, edited, seconds, progress)
    except Exception as exc:
        _failure(store, loaded, run_id, edit_id, prompt, program, "failed", "error", f"{type(exc).__name__}: {exc}",
                 seconds)
        raise
    seconds["total"] = time.perf_counter() - started
    return EditRun("succeeded", run_id, seq_id, edit_id, store.uri(rel), prompt, program, edited, seconds=seconds,
                   bytes=sizes)


def schema_error_message(exc: Exception, source: str) -> str:
    """A one-line message naming each bad field of a command file (pydantic) or where the JSON broke."""
    if isinstance(exc, json.JSONDecodeError):
        return f"{source}: not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno})"
    assert isinstance(exc, pydantic.ValidationError)
    parts = []
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        parts.append(f"{where}: {err['msg']}")
    return f"{source}: {len(parts)} schema error(s): " + "; ".join(parts)


def new_edit_run_id() -> str:
    """A fresh run id for a batch of edits (``edit-<UTC time>``)."""
    return new_run_id("edit")
