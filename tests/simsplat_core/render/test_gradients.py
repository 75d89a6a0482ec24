"""Gradients: CPU backend vs the reference's autograd, and finite differences (float64 gradcheck)."""

from __future__ import annotations

import pytest
import torch

from simsplat_core.render import isect_tiles, rasterization, rasterize_to_pixels, tile_grid
from simsplat_core.render.fused_projection import project_gaussians_fused
from simsplat_core.render.projection import project_gaussians_torch

from .scenes import cameras, edge_case_scene, random_scene


def weighted_loss(colors: torch.Tensor, alphas: torch.Tensor) -> torch.Tensor:
    """A loss whose gradient differs per pixel and channel."""
    g = torch.Generator().manual_seed(123)
    w_col = torch.rand(colors.shape, generator=g, dtype=colors.dtype) - 0.3
    w_alpha = torch.rand(alphas.shape, generator=g, dtype=alphas.dtype) - 0.5
    return (colors * w_col).sum() + (alphas * w_alpha).sum()


def grads_of(scene, backend: str, **kwargs) -> dict[str, torch.Tensor]:
    leafy = scene.with_grad()
    bgs = kwargs.pop("backgrounds", None)
    bgs = None if bgs is None else bgs.clone().requires_grad_(True)
    colors, alphas, meta = rasterization(*leafy.args(), backend=backend, backgrounds=bgs, **kwargs)
    meta.means2d.retain_grad()
    weighted_loss(colors, alphas).backward()
    out = {name: t.grad for name, t in leafy.params().items()}
    out["means2d"] = meta.means2d.grad
    if bgs is not None:
        out["backgrounds"] = bgs.grad
    return out


def assert_grads_close(got: dict, want: dict, rtol: float) -> None:
    for name, ref in want.items():
        if ref is None:  # e.g. colors in render_mode "D"
            assert got[name] is None or not bool(got[name].any()), name
            continue
        scale = float(ref.abs().max()) + 1e-12
        err = float((got[name] - ref).abs().max())
        assert err <= rtol * scale, f"{name}: max error {err:.3g} vs max |grad| {scale:.3g}"


@pytest.mark.parametrize("render_mode", ["RGB", "RGB+ED"])
@pytest.mark.parametrize("n_cams", [1, 2])
def test_float32_gradients_match_reference(render_mode: str, n_cams: int) -> None:
    scene = random_scene(50, n_cams=n_cams, dims=3, seed=31 + n_cams)
    bgs = torch.rand(n_cams, 3, generator=torch.Generator().manual_seed(2))
    got = grads_of(scene, "cpu", render_mode=render_mode, backgrounds=bgs)
    want = grads_of(scene, "reference", render_mode=render_mode, backgrounds=bgs)
    assert_grads_close(got, want, rtol=2e-4)


def test_edge_case_gradients_match_reference() -> None:
    scene = edge_case_scene(n_cams=2, dims=5)
    got = grads_of(scene, "cpu", render_mode="RGB+ED")
    want = grads_of(scene, "reference", render_mode="RGB+ED")
    assert_grads_close(got, want, rtol=2e-4)
    assert bool((got["means"][:4] == 0).all())  # culled everywhere: no gradient (and no NaN)
    assert all(bool(torch.isfinite(g).all()) for g in got.values())


def test_float64_gradients_match_reference_tightly() -> None:
    scene = random_scene(40, n_cams=2, dims=2, seed=12, dtype=torch.float64)
    got = grads_of(scene, "cpu", render_mode="D")
    want = grads_of(scene, "reference", render_mode="D")
    assert_grads_close(got, want, rtol=1e-9)


def test_means2d_grad_for_densification() -> None:
    scene = random_scene(30, n_cams=2, seed=2)
    got = grads_of(scene, "cpu")
    g2d = got["means2d"]
    assert g2d is not None and g2d.shape == (2, 30, 2)
    _, _, meta = rasterization(*scene.args(), backend="cpu")
    assert bool((g2d[meta.radii == 0] == 0).all())
    assert float(g2d[meta.radii > 0].abs().sum()) > 0


def test_gradcheck_compositing_function() -> None:
    """Finite differences of rasterize_to_pixels alone (binning fixed), float64."""
    dt = torch.float64
    g = torch.Generator().manual_seed(5)
    n_cams, n, width, height, tile = 2, 4, 9, 7, 4
    means2d = torch.rand(n_cams, n, 2, generator=g, dtype=dt) * torch.tensor([width, height], dtype=dt)
    a = 0.08 + 0.1 * torch.rand(n_cams, n, generator=g, dtype=dt)
    c = 0.08 + 0.1 * torch.rand(n_cams, n, generator=g, dtype=dt)
    b = 0.3 * torch.sqrt(a * c) * (torch.rand(n_cams, n, generator=g, dtype=dt) - 0.5)
    conics = torch.stack([a, b, c], dim=-1)
    colors = torch.rand(n_cams, n, 3, generator=g, dtype=dt)
    opacities = 0.3 + 0.5 * torch.rand(n_cams, n, generator=g, dtype=dt)
    depths = torch.rand(n_cams, n, generator=g, dtype=dt)
    radii = torch.full((n_cams, n), 6, dtype=torch.int32)
    tw, th = tile_grid(width, height, tile)
    isects = isect_tiles(means2d, radii, depths, tile, tw, th)
    bgs = torch.rand(n_cams, 3, generator=g, dtype=dt)

    def composite(m, q, col, op, bg):
        return rasterize_to_pixels(m, q, col, op, width, height, tile, isects.isect_offsets, isects.flatten_ids, bg)

    inputs = [t.clone().requires_grad_(True) for t in (means2d, conics, colors, opacities, bgs)]
    assert torch.autograd.gradcheck(composite, inputs, eps=1e-6, atol=1e-6, rtol=1e-5)


@pytest.mark.parametrize("render_mode", ["RGB", "RGB+ED"])
def test_gradcheck_full_rasterization(render_mode: str) -> None:
    dt = torch.float64
    g = torch.Generator().manual_seed(3)
    means = torch.tensor([[0.0, 0.0, 3.0], [0.3, -0.2, 4.0], [-0.4, 0.1, 5.0]], dtype=dt)
    quats = torch.randn(3, 4, generator=g, dtype=dt)
    scales = torch.tensor([[0.3, 0.2, 0.25], [0.4, 0.3, 0.2], [0.5, 0.5, 0.3]], dtype=dt)
    opacities = torch.tensor([0.6, 0.5, 0.7], dtype=dt)
    colors = torch.rand(3, 3, generator=g, dtype=dt)
    viewmats = torch.eye(4, dtype=dt)[None]
    Ks = torch.tensor([[[8.0, 0.0, 4.0], [0.0, 8.0, 3.0], [0.0, 0.0, 1.0]]], dtype=dt)
    bgs = torch.tensor([[0.1, 0.2, 0.3]], dtype=dt)

    def render(m, q, s, o, c):
        col, alpha, _ = rasterization(m, q, s, o, c, viewmats, Ks, 8, 6, render_mode=render_mode, backgrounds=bgs,
                                      backend="cpu")
        return col, alpha

    inputs = [t.clone().requires_grad_(True) for t in (means, quats, scales, opacities, colors)]
    assert torch.autograd.gradcheck(render, inputs, eps=1e-6, atol=1e-5, rtol=1e-4)


def test_fused_projection_matches_torch_projection() -> None:
    scene = random_scene(300, n_cams=3, seed=17, dtype=torch.float64, depth=(-1.0, 9.0))
    results = []
    for project in (project_gaussians_torch, project_gaussians_fused):
        leafy = scene.with_grad()
        proj = project(leafy.means, leafy.quats, leafy.scales, scene.viewmats, scene.Ks, scene.width, scene.height)
        g = torch.Generator().manual_seed(0)
        loss = sum((t * torch.randn(t.shape, generator=g, dtype=t.dtype)).sum()
                   for t in (proj.means2d, proj.conics, proj.depths))
        loss.backward()
        results.append((proj, leafy.means.grad, leafy.quats.grad, leafy.scales.grad))
    (p_t, *g_t), (p_f, *g_f) = results
    assert torch.equal(p_t.radii, p_f.radii)
    for a, b in ((p_t.means2d, p_f.means2d), (p_t.conics, p_f.conics), (p_t.depths, p_f.depths), *zip(g_t, g_f)):
        torch.testing.assert_close(a, b, rtol=1e-10, atol=1e-10)


def test_camera_gradients_use_torch_projection() -> None:
    """viewmats/Ks that require grad get gradients (torch projection path) equal to the reference's."""
    scene = random_scene(40, n_cams=2, seed=23, dtype=torch.float64)
    grads = []
    for backend in ("cpu", "reference"):
        viewmats = scene.viewmats.clone().requires_grad_(True)
        Ks = scene.Ks.clone().requires_grad_(True)
        colors, alphas, _ = rasterization(scene.means, scene.quats, scene.scales, scene.opacities, scene.colors,
                                          viewmats, Ks, scene.width, scene.height, backend=backend)
        weighted_loss(colors, alphas).backward()
        grads.append((viewmats.grad, Ks.grad))
    for got, want in zip(*grads):
        torch.testing.assert_close(got, want, rtol=1e-8, atol=1e-8)


def test_no_nan_gradients_for_degenerate_inputs() -> None:
    viewmats, Ks = cameras(1, 16, 12)
    means = torch.tensor([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.1, 0.0, 2.0]], requires_grad=True)
    quats = torch.tensor([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 2.0], [0.5, 0.5, 0.5, 0.5]], requires_grad=True)
    scales = torch.tensor([[0.1, 0.1, 0.1], [1e-6, 1e-6, 1e-6], [50.0, 50.0, 50.0]], requires_grad=True)
    opacities = torch.tensor([0.5, 0.5, 0.5], requires_grad=True)
    colors = torch.rand(3, 3, requires_grad=True)
    col, alpha, _ = rasterization(means, quats, scales, opacities, colors, viewmats, Ks, 16, 12,
                                  render_mode="RGB+ED", backend="cpu")
    (col.sum() + alpha.sum()).backward()
    for t in (means, quats, scales, opacities, colors):
        assert bool(torch.isfinite(t.grad).all())
