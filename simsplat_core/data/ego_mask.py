"""Masks of the ego car's own body in its camera images (``CameraImage.valid_mask``).

Side and rear cameras of a test car see its hood, doors and mirrors; reconstructed as scenery they would
follow the ego everywhere. A mask is given per camera as polygons in normalised image coordinates
(``u = x / width``, ``v = y / height``, both in ``[0, 1]``), so the same polygon fits any image scale.
``DDAD_EGO_BODY`` holds the polygons of the DDAD rig, placed by eye on the public DGP sample's images (a few
per cent of the image height of slack); other rigs pass their own polygons (``ego_polygons_from_json``).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from simsplat_core.data.errors import CorruptLogError

#: ``[(u, v), ...]`` polygons of the ego body per camera name.
EgoPolygons = Mapping[str, Sequence[Sequence[tuple[float, float]]]]

#: The ego body in DDAD's six cameras (CAMERA_01 front narrow sees none; 05/06 front sides, 07/08 rear
#: sides and 09 rear see doors, fenders and the trunk at the bottom of the image).
DDAD_EGO_BODY: dict[str, tuple[tuple[tuple[float, float], ...], ...]] = {
    "CAMERA_01": (),
    "CAMERA_05": (((0.0, 0.90), (0.35, 0.83), (0.7, 0.83), (1.0, 0.85), (1.0, 1.0), (0.0, 1.0)),),
    "CAMERA_06": (((0.0, 0.90), (0.15, 0.87), (0.4, 0.85), (0.6, 0.87), (0.8, 0.90), (1.0, 0.94), (1.0, 1.0),
                   (0.0, 1.0)),),
    "CAMERA_07": (((0.0, 0.58), (0.3, 0.63), (0.6, 0.72), (0.8, 0.79), (1.0, 0.86), (1.0, 1.0), (0.0, 1.0)),),
    "CAMERA_08": (((0.0, 0.92), (0.3, 0.80), (0.6, 0.68), (0.8, 0.62), (1.0, 0.57), (1.0, 1.0), (0.0, 1.0)),),
    "CAMERA_09": (((0.0, 0.92), (0.15, 0.84), (0.3, 0.79), (0.5, 0.77), (0.7, 0.79), (0.85, 0.85), (1.0, 0.93),
                   (1.0, 1.0), (0.0, 1.0)),),
}


def polygon_valid_mask(polygons: Sequence[Sequence[tuple[float, float]]], width: int, height: int) -> np.ndarray | None:
    """``[H, W]`` bool: ``False`` inside any of ``polygons`` (normalised ``(u, v)``), ``None`` without polygons."""
    if not polygons:
        return None
    invalid = np.zeros((height, width), dtype=np.uint8)
    for polygon in polygons:
        pts = np.asarray(polygon, dtype=np.float64).reshape(-1, 2) * [width, height]
        cv2.fillPoly(invalid, [np.round(pts).astype(np.int32)], 1)
    return invalid == 0


def ego_polygons_from_json(path: Path) -> dict[str, list[list[tuple[float, float]]]]:
    """User-given ego-body polygons: a JSON object ``{camera: [[[u, v], ...], ...]}`` (normalised coordinates).

    Raises:
        CorruptLogError: not that shape, or a coordinate outside ``[0, 1]`` (names the file and the camera).
    """
    try:
        doc = json.loads(Path(path).read_text())
    except json.JSONDecodeError as exc:
        raise CorruptLogError(path, f"line {exc.lineno}", f"not valid JSON: {exc.msg}") from exc
    if not isinstance(doc, dict):
        raise CorruptLogError(path, "document", "expected an object {camera: [polygon, ...]}")
    polygons: dict[str, list[list[tuple[float, float]]]] = {}
    for camera, polys in doc.items():
        try:
            arrays = [np.asarray(p, dtype=np.float64) for p in polys]
        except (TypeError, ValueError):
            raise CorruptLogError(path, f"field {camera!r}", "expected a list of [[u, v], ...] polygons") from None
        for a in arrays:
            if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < 3 or not ((a >= 0) & (a <= 1)).all():
                raise CorruptLogError(path, f"field {camera!r}",
                                      "each polygon needs >= 3 [u, v] points with coordinates in [0, 1]")
        polygons[camera] = [[(float(u), float(v)) for u, v in a] for a in arrays]
    return polygons
