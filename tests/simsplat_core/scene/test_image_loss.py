"""The reconstruction's image loss: object weighting and the object-coverage term against instance masks."""

from __future__ import annotations

import dataclasses

import pytest
import torch

from simsplat_core.scene import ReconstructionConfig
from simsplat_core.scene.config import LossWeights
from simsplat_core.scene.losses import valid_mean
from simsplat_core.scene.render import SceneRender
from simsplat_core.scene.trainer import image_loss
from simsplat_core.scene.views import ViewBatch, view_batches
from simsplat_core.types import SceneLog


@pytest.fixture(scope="module")
def batch(tiny_log: SceneLog) -> ViewBatch:
    """The first view batch whose instance mask shows an object and some background."""
    for b in view_batches(tiny_log):
        objects = b.instance > 0
        if bool(objects.any()) and not bool(objects.all()):
            return b
    pytest.skip("no frame of the tiny log shows an object")


def _render(batch: ViewBatch, coverage: torch.Tensor) -> SceneRender:
    """A render with the ground-truth colours and ``coverage [C, H, W]`` as its object-coverage channel."""
    c, h, w = coverage.shape
    return SceneRender(rgb=batch.rgb.clone(), alpha=torch.ones(c, h, w, 1), depth=torch.zeros(c, h, w, 1),
                       node_id=None, extra=coverage[..., None].clone().requires_grad_(True))


def _config(object_mask: float) -> ReconstructionConfig:
    return dataclasses.replace(ReconstructionConfig(), loss=LossWeights(object_mask=object_mask))


def test_default_config_supervises_object_coverage() -> None:
    assert ReconstructionConfig().loss.object_mask > 0


def test_coverage_term_is_weighted_l1_against_the_object_mask(batch: ViewBatch) -> None:
    objects = (batch.instance > 0).float()
    right = _render(batch, objects)
    wrong = _render(batch, 1.0 - objects)  # covers the background, misses every object pixel
    for weight in (0.5, 2.0):
        loss_right, _ = image_loss(right, batch, _config(weight))
        loss_wrong, _ = image_loss(wrong, batch, _config(weight))
        assert float(loss_right) == pytest.approx(0.0, abs=1e-6)  # perfect colours and coverage
        assert float(loss_wrong) == pytest.approx(weight * 1.0, rel=1e-5)  # every pixel off by 1
    off, _ = image_loss(wrong, batch, _config(0.0))
    assert float(off) == pytest.approx(0.0, abs=1e-6)


def test_coverage_gradient_pulls_objects_in_and_background_out(batch: ViewBatch) -> None:
    objects = batch.instance > 0
    half = _render(batch, torch.full(objects.shape, 0.5))
    loss, _ = image_loss(half, batch, _config(1.0))
    loss.backward()
    grad = half.extra.grad[..., 0]
    assert bool((grad[objects] < 0).all())  # more coverage on object pixels lowers the loss
    assert bool((grad[~objects] > 0).all())  # less coverage on background pixels lowers it


def test_no_coverage_term_without_instance_masks(batch: ViewBatch) -> None:
    no_masks = dataclasses.replace(batch, instance=None)
    wrong = _render(batch, torch.ones(batch.instance.shape))
    loss, _ = image_loss(wrong, no_masks, _config(1.0))
    assert float(loss) == pytest.approx(0.0, abs=1e-6)


def test_masked_pixels_do_not_count_in_the_colour_loss(batch: ViewBatch) -> None:
    valid = torch.ones(batch.rgb.shape[:3], dtype=torch.bool)
    valid[:, : valid.shape[1] // 2] = False  # the top half is, say, the ego car's body
    rgb = batch.rgb.clone()
    rgb[:, : valid.shape[1] // 2] = 1.0 - rgb[:, : valid.shape[1] // 2]  # wrong only where masked
    render = SceneRender(rgb=rgb, alpha=torch.ones(*valid.shape, 1), depth=torch.zeros(*valid.shape, 1),
                         node_id=None, extra=None)
    config = dataclasses.replace(ReconstructionConfig(), loss=LossWeights(object_mask=0.0, depth=0.0))
    masked = dataclasses.replace(batch, valid=valid)
    loss_masked, mse_masked = image_loss(render, masked, config)
    loss_all, mse_all = image_loss(render, batch, config)
    assert float(mse_masked) == pytest.approx(0.0, abs=1e-9) and float(mse_all) > 0.01
    assert float(loss_all) > 0.05
    assert float(loss_masked) < 0.2 * float(loss_all)  # D-SSIM windows at the mask border still see both halves


def test_valid_mean_averages_over_valid_pixels_only() -> None:
    values = torch.tensor([[[1.0, 3.0], [5.0, 100.0]]])  # [1, 2, 2]
    valid = torch.tensor([[[True, True], [True, False]]])
    assert float(valid_mean(values, valid)) == pytest.approx(3.0)
    assert float(valid_mean(values[..., None].expand(1, 2, 2, 3), valid)) == pytest.approx(3.0)
    assert float(valid_mean(values, None)) == pytest.approx(27.25)
