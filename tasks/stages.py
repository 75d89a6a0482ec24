"""Which stages each stored log goes through, decided once from what the log holds.

Every stored log is aligned (motion and location language come from its tracks and map), but

* reconstruction needs camera images: a log without pixels (the Argoverse 2 sample: annotations,
  poses, calibration and map only) skips it and is aligned straight from its log (object nodes from
  its tracks, no Gaussians, no appearance);
* the grounding benchmark needs the synthetic world's ground truth (captions, instance masks):
  real logs skip it.

A skipped stage is a decision with a reason that the flows report ("skipped: no camera images"),
never an error; a missing input is (``resolve_seq_ids``: the store's logs, scenes or language scenes,
checked by ``storage.inventory``). ``plan_alignment`` decides what the alignment flow does. Not Prefect
tasks: they read a manifest per log and take milliseconds, so the CLI checks them before starting a flow.
"""

from __future__ import annotations

from dataclasses import dataclass

from simsplat_core.types import SYNTHETIC_SOURCE
from storage import ArtifactStore, list_scenes, require_log_manifest
from storage.inventory import LOG, SCENE, Requirement, require_sequences

#: The per-log stages a flow may skip (alignment is never skipped: every log gets motion and location).
STAGES: tuple[str, ...] = ("reconstruct", "evaluate")
NO_IMAGES = "no camera images"
NO_GROUND_TRUTH = "no ground-truth captions (real log)"


@dataclass(frozen=True)
class LogStages:
    """The stages of one stored log; a stage runs when its reason is ``""``.

    Attributes:
        seq_id, source: the log (``source`` as stored: ``synthetic``, ``waymo``, ``av2``).
        images: camera images with pixels in the log.
        skip_reconstruct: why the log is not reconstructed (``""``: it is).
        skip_evaluate: why the grounding benchmark leaves it out (``""``: it is evaluated).
    """

    seq_id: str
    source: str
    images: int
    skip_reconstruct: str = ""
    skip_evaluate: str = ""

    @property
    def reconstructs(self) -> bool:
        return not self.skip_reconstruct

    @property
    def evaluates(self) -> bool:
        return not self.skip_evaluate

    def reasons(self) -> dict[str, str]:
        """``stage -> reason`` of every stage (``""``: the stage runs)."""
        return {"reconstruct": self.skip_reconstruct, "evaluate": self.skip_evaluate}

    def skipped(self, stages: tuple[str, ...] = STAGES) -> dict[str, str]:
        """``stage -> reason`` of the stages among ``stages`` that this log skips."""
        return {stage: reason for stage, reason in self.reasons().items() if reason and stage in stages}


def decide_stages(seq_id: str, source: str, images: int) -> LogStages:
    """The stages of a log of ``source`` holding ``images`` camera images with pixels."""
    skip_reconstruct = "" if images > 0 else NO_IMAGES
    skip_evaluate = "" if source == SYNTHETIC_SOURCE and images > 0 else (skip_reconstruct or NO_GROUND_TRUTH)
    return LogStages(seq_id, source, images, skip_reconstruct, skip_evaluate)


def resolve_seq_ids(store_root: str, seq_ids: list[str] | None = None, needs: Requirement = LOG) -> list[str]:
    """``seq_ids`` (default: every sequence of the store with ``needs``' artifact: a complete log, a reconstructed
    scene, a language scene), checked against the store (``storage.inventory.require_sequences``).

    Raises:
        MissingInputError: the store holds no log (saying how to add one), or a chosen sequence lacks the artifact
            (naming it, those that have it and the command that makes it).
    """
    return require_sequences(ArtifactStore(store_root), seq_ids, needs)


def plan_stages(store_root: str, seq_ids: list[str]) -> list[LogStages]:
    """``decide_stages`` for each stored log, in the order given.

    Raises:
        FileNotFoundError: a log is not (completely) in the store (named).
    """
    store = ArtifactStore(store_root)
    plans = []
    for seq_id in seq_ids:
        manifest = require_log_manifest(store, seq_id)
        images = int(manifest.get("images", {}).get("count", 0))
        plans.append(decide_stages(seq_id, str(manifest.get("source", "")), images))
    return plans


@dataclass(frozen=True)
class AlignmentPlan:
    """What the alignment flow will do: the aligner's training logs and the ``(seq_id, scene_hash)`` targets.

    Attributes:
        training_seq_ids: every log in the store (the aligner trains on all of them).
        stages: the stages of the chosen logs.
        targets: per chosen log its newest reconstructed scene, ``None`` for a log without camera images.
    """

    training_seq_ids: list[str]
    stages: list[LogStages]
    targets: list[tuple[str, str | None]]


def plan_alignment(store_root: str, seq_ids: list[str] | None = None) -> AlignmentPlan:
    """The ``AlignmentPlan`` of aligning ``seq_ids`` (default: every log) in the store; no Prefect needed,
    so the CLI checks it before starting a flow.

    Raises:
        MissingInputError: no log in the store, or a chosen log is unknown or has camera images but no
            reconstructed scene (named, with the command that makes one).
    """
    store = ArtifactStore(store_root)
    every = resolve_seq_ids(store_root)
    stages = plan_stages(store_root, resolve_seq_ids(store_root, seq_ids))
    with_images = [p.seq_id for p in stages if p.reconstructs]
    if with_images:  # aligned through their reconstructed scene: it must be there
        require_sequences(store, with_images, SCENE)
    targets = [(p.seq_id, list_scenes(store, p.seq_id)[-1] if p.reconstructs else None) for p in stages]
    return AlignmentPlan(every, stages, targets)
