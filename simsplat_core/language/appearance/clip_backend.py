"""Image-text (CLIP-style) appearance embedder on user-supplied local weights.

Nothing is downloaded. Two kinds of weight file work:

* a **TorchScript** archive whose module exports ``encode_image(images [N, 3, S, S]) -> [N, D]``
  (e.g. ``torch.jit.script`` / ``torch.jit.trace`` of a CLIP visual tower); needs only torch;
* an **open_clip checkpoint** (``.pt`` / ``.bin`` / ``.safetensors``) for the architecture named by
  ``model``; needs ``pip install open_clip_torch``.

The path comes from ``weights_path`` or the ``SIMSPLAT_CLIP_WEIGHTS`` environment variable. When the
package or the weights are missing, the constructor raises ``AppearanceBackendUnavailable`` saying
which and how to provide it.

Preprocessing follows the masked-crop practice of LangSplat: pixels outside the object mask are
replaced by the normalisation mean (zero after normalising), the crop is padded to a square and
resized to ``image_size``, then normalised with the CLIP mean and std. Image features are only
comparable with the *same* model's text tower (``language.text.ClipTextEncoder``), not with E5.
"""

from __future__ import annotations

import logging
import os
import zipfile
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
import torch

from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.language.text import l2_normalise

logger = logging.getLogger(__name__)

WEIGHTS_ENV = "SIMSPLAT_CLIP_WEIGHTS"
CLIP_MEAN = (0.48145466, 0.4578275, 0.40821073)
CLIP_STD = (0.26862954, 0.26130258, 0.27577711)


class AppearanceBackendUnavailable(RuntimeError):
    """An optional appearance backend's package or weights are missing; the message says what to provide."""


def is_torchscript_archive(path: Path) -> bool:
    """True when ``path`` is a TorchScript zip archive (it holds a ``code/`` directory)."""
    if not zipfile.is_zipfile(path):
        return False
    with zipfile.ZipFile(path) as archive:
        return any("/code/" in name or name.startswith("code/") for name in archive.namelist())


def preprocess_crops(crops: Sequence[ObjectCrop], image_size: int = 224) -> torch.Tensor:
    """Masked, square-padded, resized and normalised crops: ``[N, 3, image_size, image_size]`` float32."""
    mean = np.asarray(CLIP_MEAN, dtype=np.float32)
    std = np.asarray(CLIP_STD, dtype=np.float32)
    out = np.empty((len(crops), 3, image_size, image_size), dtype=np.float32)
    for i, crop in enumerate(crops):
        rgb = np.where(crop.mask[..., None], np.clip(crop.rgb, 0.0, 1.0), mean).astype(np.float32)
        h, w = rgb.shape[:2]
        side = max(h, w, 1)
        square = np.empty((side, side, 3), dtype=np.float32)
        square[:] = mean
        y0, x0 = (side - h) // 2, (side - w) // 2
        square[y0 : y0 + h, x0 : x0 + w] = rgb
        interp = cv2.INTER_AREA if side > image_size else cv2.INTER_CUBIC
        resized = cv2.resize(square, (image_size, image_size), interpolation=interp)
        out[i] = ((resized - mean) / std).transpose(2, 0, 1)
    return torch.from_numpy(out)


def _resolve_weights(weights_path: str | os.PathLike | None) -> Path:
    raw = weights_path if weights_path is not None else os.environ.get(WEIGHTS_ENV)
    if not raw:
        raise AppearanceBackendUnavailable(
            "the CLIP appearance backend needs local weights and none were given: pass "
            f"OpenClipEmbedder(weights_path=...) or set {WEIGHTS_ENV} to an open_clip checkpoint "
            "(.pt/.bin/.safetensors, used with pip install open_clip_torch) or a TorchScript file "
            "exporting encode_image; weights are never downloaded"
        )
    path = Path(raw).expanduser()
    if not path.is_file():
        raise AppearanceBackendUnavailable(
            f"CLIP weights file {str(path)!r} does not exist; copy the checkpoint there or point "
            f"weights_path / {WEIGHTS_ENV} at it"
        )
    return path


class OpenClipEmbedder:
    """CLIP image features of masked object crops (``AppearanceEmbedder``).

    Args:
        weights_path: local weight file (see the module docstring); ``None`` reads ``SIMSPLAT_CLIP_WEIGHTS``.
        model: open_clip architecture name for checkpoint files (ignored for TorchScript).
        image_size: input resolution of the image tower.
        batch_size: crops per forward pass.
    Raises:
        AppearanceBackendUnavailable: no weights path, a missing file, or ``open_clip`` not installed
            for a checkpoint that needs it.
    """

    def __init__(
        self,
        weights_path: str | os.PathLike | None = None,
        model: str = "ViT-B-32",
        image_size: int = 224,
        batch_size: int = 32,
    ) -> None:
        path = _resolve_weights(weights_path)
        self.image_size = image_size
        self.batch_size = batch_size
        if is_torchscript_archive(path):
            module = torch.jit.load(str(path), map_location="cpu").eval()
            if not hasattr(module, "encode_image"):
                raise AppearanceBackendUnavailable(f"TorchScript file {str(path)!r} does not export encode_image")
            self._encode = module.encode_image
            self.name = f"clip-ts:{path.name}"
        else:
            try:
                import open_clip  # noqa: PLC0415  # optional CLIP backend
            except ImportError as exc:
                raise AppearanceBackendUnavailable(
                    f"loading the CLIP checkpoint {str(path)!r} needs the open_clip package: "
                    "pip install open_clip_torch (or pass a TorchScript file exporting encode_image)"
                ) from exc
            try:
                clip_model = open_clip.create_model(model, pretrained=str(path), device="cpu").eval()
            except Exception as exc:  # wrong architecture / corrupt file: open_clip raises many types
                raise AppearanceBackendUnavailable(
                    f"open_clip could not load {str(path)!r} as a {model!r} checkpoint: {exc}"
                ) from exc
            self._encode = clip_model.encode_image
            self.name = f"clip:{model}:{path.name}"
        with torch.no_grad():
            probe = self._encode(torch.zeros(1, 3, image_size, image_size))
        self.dim = int(probe.shape[-1])
        logger.info("CLIP appearance backend %s (%d-d)", self.name, self.dim)

    def embed(self, crops: Sequence[ObjectCrop]) -> np.ndarray:
        """``[N, dim]`` unit image features of the masked crops."""
        if not crops:
            return np.zeros((0, self.dim), dtype=np.float32)
        rows = []
        with torch.no_grad():
            for start in range(0, len(crops), self.batch_size):
                batch = preprocess_crops(crops[start : start + self.batch_size], self.image_size)
                rows.append(self._encode(batch).float().cpu().numpy())
        return l2_normalise(np.concatenate(rows))
