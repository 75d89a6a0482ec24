"""The synthetic scenes an evaluation edits: each sequence's editing context and its ground truth.

Shared by the editing benchmark (``tasks.editing_eval``) and the motion benchmark (``tasks.motion_eval``):

    scene = load_truth_scene(store, seq_id, engine=engine, bank=bank)   # scene.loaded.ctx, scene.truth
    pools = asset_pools(bank)                                           # what insert prompts may ask for
"""

from __future__ import annotations

from dataclasses import dataclass

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.eval.editing.observation import AssetLook
from simsplat_core.eval.editing.plans import AssetPools
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.motion.predictor import MotionPredictor
from storage import ArtifactStore, read_scene_log
from tasks.stored_edits import LoadedEdit, load_edit_context


@dataclass(frozen=True)
class TruthScene:
    """One sequence: its editing context (``loaded.ctx``) and its ground truth (the log with images)."""

    loaded: LoadedEdit
    truth: SceneTruth


def load_truth_scene(store: ArtifactStore, seq_id: str, *, engine: QueryEngine | None = None,
                     bank: AssetBank | None = None, predictor: MotionPredictor | None = None) -> TruthScene:
    """The editing context of ``seq_id`` (``tasks.stored_edits.load_edit_context``) and its :class:`SceneTruth` with the
    reconstructed graph's node ids.

    Raises:
        FileNotFoundError: a log, language scene or scene is missing (named).
    """
    loaded = load_edit_context(store, seq_id, engine=engine, bank=bank, predictor=predictor)
    log = read_scene_log(store, seq_id)
    nodes = {n.object_id: n.node_id for n in loaded.ctx.graph.object_nodes}
    return TruthScene(loaded, SceneTruth.from_log(log, nodes))


def asset_pools(bank: AssetBank) -> AssetPools:
    """The looks of the bank's assets, for insert prompts."""
    return AssetPools.from_bank([AssetLook.of_asset(a) for a in bank.assets])


__all__ = ["TruthScene", "asset_pools", "load_truth_scene"]
