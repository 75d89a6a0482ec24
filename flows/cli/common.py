"""What several ``simsplat`` command groups share: option types, running a flow with progress bars, turning the
user's settings into configs, and checking the store before any work starts (a bad parameter, not a traceback)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any

import typer

from flows.runtime import RunnerKind

VLMOption = Annotated[str, typer.Option(help="VLM client of the mining loop: rule (built-in, offline) or openai "
                                        "(SIMSPLAT_VLM_URL, SIMSPLAT_VLM_MODEL, SIMSPLAT_VLM_API_KEY).")]
RunnerOption = Annotated[RunnerKind, typer.Option(help="Where per-sequence tasks run: a local Ray cluster or threads.")]
WorkersOption = Annotated[int | None, typer.Option(help="Parallel workers (default: all CPUs).")]
JsonOption = Annotated[bool, typer.Option("--json", help="Print the result as one JSON object on stdout.")]
RunDirOption = Annotated[str, typer.Option(help="Run directory: tables/*.parquet + tables/*.md + manifest.json.")]
AlignedSeqOption = Annotated[list[str] | None, typer.Option(help="Sequence (repeatable; default: every aligned log).")]
IterationsOption = Annotated[int | None, typer.Option(min=1, help="Reconstruction iterations per sequence "
                                                         "(default: the ReconstructionConfig default).")]
CaptionerOption = Annotated[str, typer.Option(
    help="Object captioner of the alignment: 'builtin' (offline) or 'vlm' (an OpenAI-compatible server "
         "from SIMSPLAT_VLM_URL / SIMSPLAT_VLM_MODEL; key in SIMSPLAT_VLM_API_KEY).")]


def option_names(values: list[str] | None) -> tuple[str, ...]:
    """Repeatable or comma-separated option values (``--format womd,parquet --format scenarionet``) as one tuple of
    names."""
    return tuple(n.strip() for v in values or () for n in v.split(",") if n.strip())


def run_flow(flow_fn: Any, runner: RunnerKind, workers: int | None, **params: Any) -> Any:
    """Run ``flow_fn`` with the chosen task runner against one shared Prefect API.

    Tasks' step progress (e.g. reconstruction iterations) is drawn live for either runner: reports of tasks in
    this process (threads) through a listener, those of Ray workers relayed through a folder
    (``flows.progress.RelayedSteps``). The Prefect server and Ray's processes end with this process even when it is
    killed outright (``flows.lifetime``).
    """
    from flows.lifetime import children_die_with_this_process
    from flows.progress import StepBars
    from flows.runtime import make_task_runner, prefect_api

    with children_die_with_this_process(), prefect_api(), StepBars(relay=runner == RunnerKind.ray):
        return flow_fn.with_options(task_runner=make_task_runner(runner, workers))(**params)


def world_config(frames: int, width: int, height: int) -> Any:
    """The ``WorldConfig`` of synthetic sequences of ``frames`` frames at ``width`` x ``height``."""
    from simsplat_core.world import WorldConfig

    return WorldConfig(num_frames=frames, width=width, height=height)


def alignment_config(captioner: str) -> Any:
    """The validated ``AlignmentConfig`` of ``--captioner`` (a VLM endpoint is checked now, not after hours)."""
    from simsplat_core.language.alignment.scene_builder import AlignmentConfig, AlignmentConfigError
    from simsplat_core.vlm import OpenAIChatConfig, VLMError

    try:
        alignment = AlignmentConfig(captioner=captioner).validate()
        if captioner == "vlm":
            OpenAIChatConfig.from_env()
    except (AlignmentConfigError, VLMError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--captioner") from exc
    return alignment


def check_vlm(vlm: str) -> None:
    """``--vlm`` names a known client, and ``openai`` has its endpoint configured (else a BadParameter)."""
    from simsplat_core.vlm.openai_chat import OpenAIChatConfig, VLMError
    from tasks.mine import VLM_KINDS

    if vlm not in VLM_KINDS:
        raise typer.BadParameter(f"unknown VLM client {vlm!r}; choose one of {list(VLM_KINDS)}", param_hint="--vlm")
    if vlm == "openai":
        try:
            OpenAIChatConfig.from_env()
        except VLMError as exc:
            raise typer.BadParameter(str(exc), param_hint="--vlm") from exc


def writable_store(store: str) -> None:
    """The store at ``store`` can be written (a probe file written and deleted at its root), else a bad parameter
    naming it and why: the disk is full, the filesystem is read-only, permission is denied, the root is a file."""
    from storage import ArtifactStore
    from storage.errors import StoreNotWritableError

    try:
        ArtifactStore(store).check_writable()
    except StoreNotWritableError as exc:
        raise typer.BadParameter(str(exc), param_hint="--store") from exc


def stored_sequences(store: str, seq: list[str] | None = None, needs: str = "log",
                     param_hint: str = "--seq") -> list[str]:
    """``seq`` (default: every sequence of ``store`` that has what ``needs`` names: ``"log"``, ``"scene"``,
    ``"language"``), checked before any work starts; a bad parameter naming the missing ones and the command that
    makes them (``storage.inventory``)."""
    from storage.errors import MissingInputError
    from storage.inventory import LANGUAGE_SCENE, LOG, SCENE
    from tasks.stages import resolve_seq_ids

    requirement = {"log": LOG, "scene": SCENE, "language": LANGUAGE_SCENE}[needs]
    try:
        return resolve_seq_ids(store, list(seq) if seq else None, requirement)
    except MissingInputError as exc:
        raise typer.BadParameter(str(exc), param_hint=param_hint) from exc


def stored_asset_bank(store: str, seq_ids: Sequence[str] | None = None) -> str:
    """The hash of ``store``'s newest asset bank; a bad parameter naming ``simsplat assets build`` when it has none.
    With ``seq_ids`` whose logs all lack cameras (edited with box-only inserts, ``tasks.stored_edits``) no bank is
    needed: ``""`` when the store has none."""
    from storage import ArtifactStore, read_log_manifest
    from storage.errors import MissingInputError
    from storage.inventory import require_asset_bank

    opened = ArtifactStore(store)
    try:
        return require_asset_bank(opened)
    except MissingInputError as exc:
        if seq_ids is not None and not any((read_log_manifest(opened, s) or {}).get("cameras") for s in seq_ids):
            return ""
        raise typer.BadParameter(str(exc), param_hint="--store") from exc
