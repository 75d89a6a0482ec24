"""Which stages each stored log goes through, decided once from what the log holds.

Every stored log is aligned (motion and location language come from its tracks and map), but

* reconstruction needs camera images: a log without pixels (the Argoverse 2 sample: annotations,
  poses, calibration and map only) skips it and is aligned straight from its log (object nodes from
  its tracks, no Gaussians, no appearance);
* the grounding benchmark needs the synthetic world's ground truth (captions, instance masks):
  real logs skip it.

A skipped stage is a decision with a reason that the flows report ("skipped: no camera images"),
never an error. Not a Prefect task: it reads a manifest per log and takes milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass

from simsplat_core.types import SYNTHETIC_SOURCE
from storage import ArtifactStore, list_logs, require_log_manifest

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


def resolve_seq_ids(store_root: str, seq_ids: list[str] | None = None) -> list[str]:
    """``seq_ids`` (default: every complete log in the store), checked against the store.

    Raises:
        ValueError: the store holds no log (saying how to add one), or a chosen log is not in it (naming
            it and the available ones).
    """
    available = list_logs(ArtifactStore(store_root))
    if not available:
        raise ValueError(f"no driving log in {store_root}/logs: generate synthetic ones (simsplat run --sequences N) "
                         "or ingest real ones (simsplat ingest SOURCE PATH, or simsplat ingest auto PATH)")
    chosen = list(seq_ids) if seq_ids else available
    unknown = [s for s in chosen if s not in available]
    if unknown:
        raise ValueError(f"no complete log {unknown} in {store_root}/logs; available: {available}")
    return chosen


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
