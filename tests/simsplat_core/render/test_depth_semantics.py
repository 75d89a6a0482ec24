"""Expected depth: one normalisation (``render.depth.finish_channels``) for every backend, with an alpha
floor that keeps nearly empty pixels from turning rounding into metres."""

from __future__ import annotations

import sys
import types

import pytest
import torch

from simsplat_core.render import gsplat_backend
from simsplat_core.render.api import rasterization
from simsplat_core.render.depth import finish_channels
from simsplat_core.render.types import ED_EPS
from tests.simsplat_core.render.scenes import random_scene


def test_low_alpha_pixel_rounding_stays_small() -> None:
    alpha = torch.tensor([1e-7, 1e-3, 0.5]).reshape(1, 3, 1, 1)
    depth = 40.0
    rounding = 1e-7  # float32 epsilon-sized error on the accumulated depth (as 1 - T carries on a GPU)
    acc = depth * alpha + rounding
    got = finish_channels(acc, alpha, "D")[0, :, 0, 0]
    assert torch.all((got - depth * torch.clamp(alpha[0, :, 0, 0] / ED_EPS, max=1.0)).abs() <= rounding / ED_EPS + 1e-4)
    floor_of_gsplat_ed = acc / alpha.clamp(min=1e-10)  # what a 1e-10 floor gives at the first pixel
    assert float(floor_of_gsplat_ed[0, 0, 0, 0] - depth) > 0.5  # metres off
    assert float(got[1]) == pytest.approx(depth, abs=1e-3) and float(got[2]) == pytest.approx(depth, abs=1e-5)


def test_reference_expected_depth_is_a_weighted_mean_of_camera_depths() -> None:
    scene = random_scene(12, n_cams=2)
    colors, alphas, meta = rasterization(*scene.args(), render_mode="RGB+ED", backend="reference")
    depth_only, _, _ = rasterization(*scene.args(), render_mode="D", backend="reference")
    torch.testing.assert_close(colors[..., -1:], depth_only)
    depth, covered = colors[..., -1], alphas[..., 0] >= ED_EPS
    visible = meta.depths[meta.radii > 0]
    assert covered.any()
    assert float(depth[covered].min()) >= float(visible.min()) - 1e-4
    assert float(depth[covered].max()) <= float(visible.max()) + 1e-4
    assert torch.all(depth[~covered].abs() <= float(visible.max()) * alphas[..., 0][~covered] / ED_EPS + 1e-6)


def test_gsplat_backend_normalises_accumulated_depth_like_the_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    """A stub gsplat returning the reference's accumulated depth: the backend's expected depth must match."""
    scene = random_scene(10, n_cams=1)
    want, want_alphas, ref_meta = rasterization(*scene.args(), render_mode="RGB+ED", backend="reference")
    accumulated = torch.cat([want[..., :-1], want[..., -1:] * want_alphas.clamp(min=ED_EPS)], dim=-1)
    modes = []

    def fake_rasterization(means, quats, scales, opacities, colors, viewmats, Ks, width, height, **kwargs):
        modes.append(kwargs["render_mode"])
        info = {"radii": ref_meta.radii[..., None].expand(-1, -1, 2), "means2d": ref_meta.means2d,
                "depths": ref_meta.depths, "conics": ref_meta.conics, "opacities": ref_meta.opacities}
        return accumulated, want_alphas, info

    monkeypatch.setitem(sys.modules, "gsplat", types.SimpleNamespace(rasterization=fake_rasterization))
    got, _, _ = gsplat_backend.rasterize_gsplat(*scene.args(), near_plane=0.01, far_plane=1e10, render_mode="RGB+ED",
                                                backgrounds=None, tile_size=16, eps2d=0.3, radius_clip=0.0)
    assert modes == ["RGB+D"]
    torch.testing.assert_close(got, want)
