"""The evaluation loop end to end on a small scene built here (a 40-frame 96 x 64 log with pixels, its initial
scene graph, a ground-truth language scene, a procedural asset bank): a correct edit passes every check, a
wrong one fails naming why, an infeasible request is refused, and the tables come out."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.procedural import procedural_asset
from simsplat_core.editing.commands import EditCommand, EditProgram, TargetRef
from simsplat_core.editing.draft import EditContext
from simsplat_core.eval.editing.evaluate import (
    METHODS,
    EvalScene,
    Method,
    editing_methods,
    evaluate_editing,
    evaluate_prompt,
)
from simsplat_core.eval.editing.outcomes import completion_table, fidelity_table
from simsplat_core.eval.editing.prompts import INFEASIBLE, PromptConfig, build_prompt_set
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.eval.grounding.gt_scene import language_scene_from_log
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from simsplat_core.scene import InitConfig
from simsplat_core.scene.init import initial_graph
from simsplat_core.world import WorldConfig, generate_log


@pytest.fixture(scope="module")
def scene() -> EvalScene:
    log = generate_log(0, WorldConfig(width=96, height=64))
    train = {img.frame_idx for img in log.images if img.split == "train"}
    graph = initial_graph(log, InitConfig(pixel_stride=2), train)
    node_of = {n.object_id: n.node_id for n in graph.object_nodes}
    encoder = default_text_encoder()
    language = language_scene_from_log(log, encoder, appearance="ground_truth")
    lut = np.arange(max(node_of.values()) + 2, dtype=np.int32) - 1  # log order -> the graph's ids
    for k, obj in enumerate(log.objects, start=1):
        lut[k + 1] = node_of[obj.object_id]
    nodes = tuple(sorted((dataclasses.replace(n, node_id=node_of[n.object_id]) for n in language.nodes),
                         key=lambda n: n.node_id))
    maps = lut[language.node_id_maps + 1] if language.node_id_maps is not None else None
    language = dataclasses.replace(language, nodes=nodes, node_id_maps=maps)
    bank = AssetBank.from_assets([procedural_asset("traffic cone", "orange"), procedural_asset("barrier", "white")])
    ctx = EditContext.create(log, graph, language, QueryEngine(encoder), bank)
    return EvalScene.prepare(SceneTruth.from_log(log, node_of), ctx)


def test_correct_edit_passes_wrong_edit_fails_infeasible_is_refused(scene: EvalScene) -> None:
    prompts = build_prompt_set([scene.truth], PromptConfig(per_category=3, infeasible=4))
    remove = next(p for p in prompts if p.kind == "remove_single")
    right = evaluate_prompt(scene, remove, METHODS["omnire-like"])  # the id-based form: the right object
    assert right.completed, right.reason
    assert right.fidelity is not None and right.fidelity.views == 4 * 3
    other = next(o for o in scene.truth.node_of_object if o not in remove.intent.targets
                 and scene.truth.agent(o).category == "vehicle")
    wrong_program = EditProgram(prompt=remove.text, commands=[
        EditCommand(op="remove", target=TargetRef(node_id=scene.truth.node_of_object[other]))])
    wrong = evaluate_prompt(scene, dataclasses.replace(remove, structured=wrong_program), METHODS["omnire-like"])
    assert not wrong.completed and f"removed ['{other}']" in wrong.reason
    absent = next(p for p in prompts if p.category == INFEASIBLE and not p.intent.structured)
    refused = evaluate_prompt(scene, absent, METHODS["ours"])
    assert refused.completed and refused.refusal and "refused" in refused.reason
    cone = next(p for p in prompts if p.category == "add_static")
    outcomes = evaluate_editing([scene], [cone], [METHODS["omnire-like"],
                                                  Method("no-inserts", dataclasses.replace(
                                                      METHODS["omnire-like"].options, ops=frozenset({"remove"})),
                                                      from_words=False)])
    assert outcomes[1].refusal == "unsupported" and not outcomes[1].completed
    table = completion_table(outcomes).to_pylist()
    assert {r["method"] for r in table} == {"omnire-like", "no-inserts"}
    assert fidelity_table(outcomes, {scene.truth.seq_id: scene.psnr_unedited}).num_rows == 14


def test_methods_are_the_editor_with_options() -> None:
    names = [m.name for m in editing_methods()]
    assert names == ["ours", "chatsim-like", "omnire-like"]
    chatsim, omnire = METHODS["chatsim-like"], METHODS["omnire-like"]
    assert chatsim.from_words and chatsim.options.grounding == "attributes" and "modify" not in chatsim.options.ops
    assert not omnire.from_words and omnire.options.grounding == "ids" and not omnire.options.allow_pedestrian_insert
    with pytest.raises(KeyError, match="known"):
        editing_methods(["ours", "nope"])
