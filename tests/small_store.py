"""A small store for tests that edit, mine or browse one synthetic log: the log, its initial scene graph as the
"reconstructed" scene, a ground-truth language scene on that graph's node ids, and a two-asset bank (a yellow
mesh sedan, an orange procedural cone). Nothing is trained, so it is written in seconds."""

from __future__ import annotations

import dataclasses

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.procedural import procedural_asset
from simsplat_core.eval.grounding.gt_scene import language_scene_from_log
from simsplat_core.language.text import default_text_encoder
from simsplat_core.scene import InitConfig
from simsplat_core.scene.init import initial_graph
from simsplat_core.types import SceneLog
from storage import ArtifactStore, write_scene, write_scene_log
from storage.assets import write_asset_bank
from storage.language_scenes import write_language_scene
from tests.simsplat_core.editing.assets.fixtures import mesh_vehicle


def write_small_store(root: str, log: SceneLog, *, scene_hash: str, model_hash: str, language_hash: str) -> None:
    """Write ``log`` and its scene, language scene (under the given hashes) and asset bank into the store at
    ``root`` (module docstring)."""
    store = ArtifactStore(root)
    write_scene_log(store, log)
    graph = initial_graph(log, InitConfig(), set(range(log.num_frames)))
    records = graph.to_records(f"{log.seq_id}/{scene_hash}")
    write_scene(store, log.seq_id, scene_hash, records, {})
    language = language_scene_from_log(log, default_text_encoder(), appearance="ground_truth")
    node_of = {n.object_id: n.node_id for n in graph.object_nodes}
    nodes = tuple(sorted((dataclasses.replace(n, node_id=node_of[n.object_id]) for n in language.nodes),
                         key=lambda n: n.node_id))
    write_language_scene(store, model_hash, language_hash,
                         dataclasses.replace(language, nodes=nodes, scene_hash=scene_hash), records)
    write_asset_bank(store, AssetBank.from_assets([mesh_vehicle("t.yellow-sedan", color="yellow"),
                                                   procedural_asset("traffic cone", "orange")]))
