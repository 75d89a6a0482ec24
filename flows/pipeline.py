"""Prefect flows. Each reads like the pipeline: fan out one task per sequence, gather, publish."""

from __future__ import annotations

import logging

from prefect import flow
from prefect.artifacts import create_markdown_artifact, create_table_artifact
from prefect.futures import as_completed

from flows.progress import FlowProgress
from simsplat_core.world import WorldConfig
from tasks.logs import StoredLog, generate_synthetic_log, ingest_real_log

logger = logging.getLogger(__name__)


def _gather(futures: list, stage: str) -> list[StoredLog]:
    """Wait for ``futures`` as they finish, reporting progress; results in submission order."""
    order = {id(f): i for i, f in enumerate(futures)}
    results: list[StoredLog | None] = [None] * len(futures)
    with FlowProgress(stage, total=len(futures)) as progress:
        for future in as_completed(futures):
            result = future.result()
            results[order[id(future)]] = result
            progress.advance(result.summary.seq_id)
    return [r for r in results if r is not None]


def _publish_logs_table(logs: list[StoredLog]) -> None:
    rows = [
        {
            "seq_id": s.summary.seq_id,
            "source": s.summary.source,
            "frames": s.summary.num_frames,
            "cameras": len(s.summary.cameras),
            "objects": sum(s.summary.objects_by_category.values()),
            "MB": round(s.bytes_on_disk / 1e6, 2),
            "seconds": s.seconds,
            "skipped": s.skipped,
        }
        for s in logs
    ]
    create_table_artifact(rows, key="logs", description="Driving logs in the store")


def generate_logs(store_root: str, seeds: list[int], config: WorldConfig) -> list[StoredLog]:
    """Fan out one generation task per seed on the flow's task runner; publish the logs table."""
    futures = [generate_synthetic_log.submit(store_root, seed, config) for seed in seeds]
    logs = _gather(futures, "generate")
    _publish_logs_table(logs)
    return logs


@flow(name="simsplat-generate-world")
def generate_world_flow(store_root: str, seeds: list[int], config: WorldConfig) -> list[StoredLog]:
    """Generate one synthetic sequence per seed into the store, in parallel."""
    return generate_logs(store_root, seeds, config)


@flow(name="simsplat-ingest")
def ingest_flow(store_root: str, source: str, paths: list[str], image_scale: float = 1.0) -> list[StoredLog]:
    """Decode real driving logs (one task per file or log directory) into the store."""
    futures = [ingest_real_log.submit(store_root, source, path, image_scale) for path in paths]
    logs = _gather(futures, f"ingest {source}")
    _publish_logs_table(logs)
    return logs


@flow(name="simsplat-main")
def main_flow(store_root: str, seeds: list[int], config: WorldConfig) -> list[StoredLog]:
    """The main job: synthetic logs in (later stages extend this flow), then a summary.

    Returns:
        one ``StoredLog`` per sequence.
    """
    logs = generate_logs(store_root, seeds, config)
    lines = ["| sequence | frames | objects | MB | s |", "|---|---|---|---|---|"]
    for s in logs:
        objects = ", ".join(f"{n} {c}" for c, n in s.summary.objects_by_category.items())
        lines.append(f"| {s.summary.seq_id} | {s.summary.num_frames} | {objects} | {s.bytes_on_disk / 1e6:.1f} | {s.seconds:.1f} |")
    create_markdown_artifact("\n".join(lines), key="main-summary", description="SIMSplat main job")
    return logs


@flow(name="simsplat-scheduled-main")
def scheduled_main_flow(
    store_root: str,
    sequences: int = 2,
    seed: int = 0,
    frames: int = 40,
    width: int = 240,
    height: int = 160,
    runner: str = "ray",
) -> list[StoredLog]:
    """Deployment entry point (``deploy/prefect.yaml``): JSON parameters in, the main flow on ``runner``.

    A deployment cannot choose a task runner per run, so this parent flow picks it and runs
    ``main_flow`` as a subflow.
    """
    from flows.runtime import RunnerKind, make_task_runner

    config = WorldConfig(num_frames=frames, width=width, height=height)
    task_runner = make_task_runner(RunnerKind(runner))
    return main_flow.with_options(task_runner=task_runner)(store_root, list(range(seed, seed + sequences)), config)
