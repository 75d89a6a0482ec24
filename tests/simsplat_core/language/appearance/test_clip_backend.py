"""The CLIP backend: clear errors when its package or weights are missing; the TorchScript plumbing."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
import torch

from simsplat_core.language.appearance.clip_backend import (
    WEIGHTS_ENV,
    AppearanceBackendUnavailable,
    OpenClipEmbedder,
    preprocess_crops,
)
from simsplat_core.language.appearance.embedders import AppearanceEmbedder
from tests.simsplat_core.language.appearance.helpers import PAINTS, make_crop, paint_vehicle


def test_no_weights_raises_clear_error(monkeypatch):
    monkeypatch.delenv(WEIGHTS_ENV, raising=False)
    with pytest.raises(AppearanceBackendUnavailable, match=f"needs local weights.*{WEIGHTS_ENV}"):
        OpenClipEmbedder()


def test_missing_weights_file_names_the_path(tmp_path):
    path = tmp_path / "ViT-B-32.pt"
    with pytest.raises(AppearanceBackendUnavailable, match="does not exist") as info:
        OpenClipEmbedder(str(path))
    assert str(path) in str(info.value)


def test_environment_variable_is_read(monkeypatch, tmp_path):
    monkeypatch.setenv(WEIGHTS_ENV, str(tmp_path / "from-env.pt"))
    with pytest.raises(AppearanceBackendUnavailable, match="from-env.pt"):
        OpenClipEmbedder()


@pytest.mark.skipif(importlib.util.find_spec("open_clip") is not None, reason="open_clip is installed here")
def test_checkpoint_without_open_clip_names_the_package(tmp_path):
    path = tmp_path / "open_clip_model.safetensors"
    path.write_bytes(b"not really a checkpoint")
    with pytest.raises(AppearanceBackendUnavailable, match="pip install open_clip_torch"):
        OpenClipEmbedder(str(path))


class _ToyImageTower(torch.nn.Module):
    """Not CLIP: a fixed pooling layer with CLIP's ``encode_image`` entry point, to test the plumbing."""

    def __init__(self) -> None:
        super().__init__()
        self.proj = torch.nn.Linear(3, 5)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.encode_image(images)

    @torch.jit.export
    def encode_image(self, images: torch.Tensor) -> torch.Tensor:
        return self.proj(images.mean(dim=(2, 3)))


def test_torchscript_file_loads_without_open_clip(tmp_path):
    path = tmp_path / "tower.ts"
    torch.manual_seed(0)
    torch.jit.save(torch.jit.script(_ToyImageTower()), str(path))
    embedder = OpenClipEmbedder(str(path), image_size=32)
    assert isinstance(embedder, AppearanceEmbedder)
    assert embedder.dim == 5 and embedder.name == "clip-ts:tower.ts"
    crops = [make_crop(*paint_vehicle(PAINTS[c]), "vehicle", (4.6, 1.8, 1.45), c) for c in ("red", "blue", "red")]
    feats = embedder.embed(crops)
    assert feats.shape == (3, 5)
    np.testing.assert_allclose(np.linalg.norm(feats, axis=1), 1.0, atol=1e-5)
    assert feats[0] @ feats[2] > feats[0] @ feats[1]


def test_torchscript_without_encode_image_is_rejected(tmp_path):
    path = tmp_path / "plain.ts"
    torch.jit.save(torch.jit.script(torch.nn.Linear(3, 3)), str(path))
    with pytest.raises(AppearanceBackendUnavailable, match="encode_image"):
        OpenClipEmbedder(str(path))


def test_preprocess_masks_pads_and_normalises():
    rgb, mask = paint_vehicle(PAINTS["red"], height=20, width=60)
    batch = preprocess_crops([make_crop(rgb, mask, "vehicle", (4.6, 1.8, 1.45), "v")], image_size=48)
    assert batch.shape == (1, 3, 48, 48) and batch.dtype == torch.float32
    assert torch.allclose(batch[0, :, 0, 0], torch.zeros(3), atol=1e-5)  # padding = normalised mean
    assert batch[0, 0].max() > 1.0  # the red body survives normalisation
