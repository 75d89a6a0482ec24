"""Schema of a language scene's per-node table (``alignment/<model_hash>/scenes/...``)."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema

NODE_LANGUAGE_SCHEMA = make_schema(
    "node_language",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("object_id", pa.string()),
        ("category", pa.string()),
        ("kind", pa.string()),  # motion codebook: "vehicle" | "pedestrian" | "" (static)
        ("has_appearance", pa.bool_()),  # nodes.f_app is real (the log had pixels of the object)
        ("has_motion", pa.bool_()),  # nodes.f_mot / f_loc are real (a moving agent with an aligner)
        ("caption", pa.string()),  # the captioner's description ("" without pixels)
        ("caption_json", pa.string()),  # AppearanceCaption fields as JSON ("" without pixels)
        ("motion_json", pa.string()),  # motion/location probabilities and auto-labels as JSON ("" if none)
    ],
)
