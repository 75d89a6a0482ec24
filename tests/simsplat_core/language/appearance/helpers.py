"""Painted test images (vehicles, pedestrians, patches) and a deterministic stand-in text encoder."""

from __future__ import annotations

import re
import zlib
from collections.abc import Sequence

import numpy as np

from simsplat_core.language.appearance.crops import ObjectCrop

GLASS = (0.2, 0.25, 0.31)
TYRE = (0.07, 0.07, 0.08)
ASPHALT = (0.3, 0.3, 0.32)
SHADE, LIT = 0.64, 1.05

#: The synthetic world's paints (``world/palette.py``), by the name the captioner must give them.
PAINTS = {
    "black": (0.05, 0.05, 0.06),
    "white": (0.9, 0.9, 0.88),
    "silver": (0.66, 0.68, 0.71),
    "gray": (0.4, 0.41, 0.43),
    "red": (0.75, 0.07, 0.07),
    "blue": (0.1, 0.22, 0.68),
    "yellow": (0.95, 0.78, 0.08),
    "green": (0.08, 0.45, 0.18),
    "orange": (0.95, 0.42, 0.05),
    "brown": (0.42, 0.26, 0.13),
    "beige": (0.78, 0.7, 0.53),
}


def shaded(rgb, factor: float) -> np.ndarray:
    return np.clip(np.asarray(rgb, dtype=np.float32) * factor, 0.0, 1.0)


def patch(rgb, factor: float = 1.0, size: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A flat ``size x size`` patch of ``rgb * factor`` with a full mask."""
    img = np.broadcast_to(shaded(rgb, factor), (size, size, 3)).copy()
    return img, np.ones((size, size), dtype=bool)


def paint_vehicle(body, faces=(SHADE, LIT), height: int = 40, width: int = 90, noise: float = 0.03, seed: int = 0):
    """A side-and-rear view of a car: body in two faces (``faces`` shading factors), glass cabin,
    two tyres, on asphalt. Returns ``rgb [H, W, 3]`` and the car's ``mask [H, W]``."""
    rng = np.random.default_rng(seed)
    h, w = height, width
    img = np.empty((h + 10, w + 10, 3), np.float32)
    img[:] = ASPHALT
    mask = np.zeros(img.shape[:2], bool)
    y_belt, y_roof = 5 + int(0.5 * h), 5 + int(0.1 * h)
    split = 5 + int(0.35 * w)
    img[y_belt : 5 + h, 5:split] = shaded(body, faces[0])  # rear face
    img[y_belt : 5 + h, split : 5 + w] = shaded(body, faces[1])  # side face
    mask[y_belt : 5 + h, 5 : 5 + w] = True
    x0, x1 = 5 + int(0.2 * w), 5 + int(0.75 * w)
    img[y_roof:y_belt, x0:x1] = shaded(GLASS, faces[1])  # windows
    img[y_roof : y_roof + 2, x0:x1] = shaded(body, faces[1] + 0.1)  # roof edge
    mask[y_roof:y_belt, x0:x1] = True
    r = max(h // 6, 2)
    for cx in (5 + int(0.22 * w), 5 + int(0.8 * w)):
        img[5 + h - r : 5 + h, cx - r : cx + r] = TYRE
    img *= (1.0 + noise * rng.standard_normal(img.shape[:2]))[..., None].astype(np.float32)
    return np.clip(img, 0, 1), mask


def paint_pedestrian(upper, lower, skin=(0.72, 0.53, 0.4), hair=(0.08, 0.06, 0.05), height: int = 60, seed: int = 0):
    """A front view of a person (head, torso + arms, trousers, shoes) on a sidewalk colour."""
    rng = np.random.default_rng(seed)
    h = height
    w = max(h // 3, 8)
    img = np.empty((h + 6, w + 6, 3), np.float32)
    img[:] = (0.63, 0.62, 0.6)
    mask = np.zeros(img.shape[:2], bool)

    def fill(y0: float, y1: float, x0: float, x1: float, rgb, factor: float = 1.0) -> None:
        ys, ye = 3 + int(y0 * h), 3 + int(y1 * h)
        xs, xe = 3 + int(x0 * w), 3 + int(x1 * w)
        img[ys:ye, xs:xe] = shaded(rgb, factor)
        mask[ys:ye, xs:xe] = True

    fill(0.0, 0.04, 0.35, 0.65, hair)
    fill(0.04, 0.13, 0.35, 0.65, skin)
    fill(0.13, 0.19, 0.43, 0.57, skin)
    fill(0.19, 0.52, 0.15, 0.85, upper, SHADE)
    fill(0.19, 0.5, 0.0, 0.15, upper, LIT)
    fill(0.19, 0.5, 0.85, 1.0, upper, LIT)
    fill(0.5, 0.55, 0.0, 0.15, skin)
    fill(0.52, 0.96, 0.2, 0.8, lower, SHADE)
    fill(0.96, 1.0, 0.2, 0.8, (0.12, 0.12, 0.13))
    img *= (1.0 + 0.03 * rng.standard_normal(img.shape[:2]))[..., None].astype(np.float32)
    return np.clip(img, 0, 1), mask


def make_crop(rgb, mask, category: str, box_size, object_id: str, frame_idx: int = 0) -> ObjectCrop:
    return ObjectCrop(rgb, mask, category, np.asarray(box_size, dtype=np.float64), frame_idx, "front", object_id)


class HashTextEncoder:
    """Deterministic bag-of-words encoder (``TextEncoder`` protocol): each word is a fixed random
    vector seeded by its CRC32; a text is the normalised sum. Shares words -> similar vectors."""

    name = "hash-bow-64"
    dim = 64

    def __init__(self) -> None:
        self.calls = 0

    def _word(self, word: str) -> np.ndarray:
        return np.random.default_rng(zlib.crc32(word.encode())).standard_normal(self.dim)

    def _encode(self, texts: Sequence[str]) -> np.ndarray:
        self.calls += 1
        out = np.zeros((len(texts), self.dim))
        for i, text in enumerate(texts):
            for word in re.findall(r"[a-z]+", text.lower()):
                out[i] += self._word(word)
        out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
        return out.astype(np.float32)

    def encode_queries(self, texts: Sequence[str]) -> np.ndarray:
        return self._encode(texts)

    def encode_passages(self, texts: Sequence[str]) -> np.ndarray:
        return self._encode(texts)
