"""Language scenes for tests: ground-truth scenes of small worlds (built by
``simsplat_core.eval.grounding.gt_scene.language_scene_from_log``) and hand-built scenes.

    log, scene = world_language_scene(7, encoder)
    scene.node(3).caption.text      # "a silver van"

Hand-built scenes (exact control over look-alikes) come from ``ObjectSpec`` s:

    scene = hand_built_scene([ObjectSpec("a", "vehicle", vehicle_caption("red", "sedan"),
                                         motion_label("a", "turning_left", "in_front_of_ego", "at_the_intersection"))],
                             encoder)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.eval.grounding.gt_scene import AppearanceSource, label_motion_features, language_scene_from_log
from simsplat_core.language.alignment.motion_training import MotionAligner
from simsplat_core.language.appearance.captioner import AppearanceCaption, caption_text
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.motion_labels import MotionLabel
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.language.text import TextEncoder, l2_normalise
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import PEDESTRIAN_MOTION
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

#: A small world for tests: a second of driving, three small cameras.
SMALL_WORLD = WorldConfig(num_frames=12, width=160, height=104)


def world_language_scene(
    seed: int,
    text_encoder: TextEncoder,
    config: WorldConfig = SMALL_WORLD,
    appearance: AppearanceSource = "captioner",
    aligner: MotionAligner | None = None,
    codebooks: MotionCodebooks | None = None,
) -> tuple[SceneLog, LanguageScene]:
    """Generate a synthetic log and its ground-truth ``LanguageScene``."""
    log = generate_log(seed, config)
    return log, language_scene_from_log(log, text_encoder, appearance, aligner, codebooks)


# ---------------------------------------------------------------------------------------------- hand-built scenes
def vehicle_caption(color: str, subtype: str, category: str = "vehicle") -> AppearanceCaption:
    """``"a red sedan"`` as the captioner would write it."""
    return AppearanceCaption(caption_text(category, subtype, (color,)), category, subtype, (color,), confidence=1.0)


def pedestrian_caption(upper: str, lower: str, subtype: str = "adult") -> AppearanceCaption:
    """``"a pedestrian in a red top and blue trousers"`` as the captioner would write it."""
    text = caption_text("pedestrian", subtype, (), upper, lower)
    return AppearanceCaption(text, "pedestrian", subtype, (upper, lower), upper, lower, 1.0)


def motion_label(object_id: str, motion: str, sector: str, context: str) -> MotionLabel:
    """An auto-label; the kind follows from the motion class (pedestrian classes are pedestrian)."""
    kind = "pedestrian" if motion in PEDESTRIAN_MOTION.names else "vehicle"
    return MotionLabel(object_id, kind, motion, sector, context, 0)


@dataclass(frozen=True)
class ObjectSpec:
    """One object of a hand-built scene: its caption (``None``: no pixels) and motion label (``None``: static)."""

    object_id: str
    category: str
    caption: AppearanceCaption | None
    label: MotionLabel | None = None


def hand_built_scene(
    specs: list[ObjectSpec],
    text_encoder: TextEncoder,
    codebooks: MotionCodebooks | None = None,
    sharpness: float = 0.9,
    image_size: tuple[int, int] = (4, 8),
    seq_id: str = "hand-built",
) -> LanguageScene:
    """A ``LanguageScene`` with one node per spec (node ``k + 1``), label-built motion features, passage
    embeddings of the captions as ``f_app``, and ``[1, 1, H, W]`` node-id maps in which node ``k + 1`` owns
    pixel ``k`` (row-major; background elsewhere)."""
    books = codebooks or MotionCodebooks.build(text_encoder)
    motion = label_motion_features({s.object_id: s.label for s in specs if s.label is not None}, books, sharpness)
    texts = [s.caption.text for s in specs if s.caption is not None]
    embedded = dict(zip(texts, l2_normalise(text_encoder.encode_passages(texts)))) if texts else {}
    height, width = image_size
    if len(specs) > height * width:
        raise ValueError(f"{len(specs)} objects do not fit one pixel each in {height}x{width}")
    maps = np.zeros((1, 1, height, width), dtype=np.int32)
    nodes = []
    for k, spec in enumerate(specs):
        maps.reshape(-1)[k] = k + 1
        nodes.append(
            NodeLanguage(
                node_id=k + 1,
                object_id=spec.object_id,
                category=spec.category,
                kind=agent_kind(spec.category) or "",
                f_app=None if spec.caption is None else embedded[spec.caption.text],
                caption=spec.caption,
                motion=motion.get(spec.object_id),
            )
        )
    return LanguageScene(seq_id, "", tuple(nodes), np.zeros(1, np.int64), ("front",), maps, text_encoder.name)
