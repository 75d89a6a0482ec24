"""CPU backend vs the dense reference: forward values over shapes, modes and edge cases."""

from __future__ import annotations

import pytest
import torch

from simsplat_core.render import rasterization

from .scenes import edge_case_scene, random_scene

ATOL = 1e-5


def render_both(scene, **kwargs):
    out_cpu = rasterization(*scene.args(), backend="cpu", **kwargs)
    out_ref = rasterization(*scene.args(), backend="reference", **kwargs)
    return out_cpu, out_ref


def assert_images_close(out_cpu, out_ref, render_mode: str = "RGB", atol: float = ATOL) -> None:
    (col_c, alpha_c, meta_c), (col_r, alpha_r, meta_r) = out_cpu, out_ref
    assert col_c.shape == col_r.shape and alpha_c.shape == alpha_r.shape
    assert torch.equal(meta_c.radii, meta_r.radii)
    torch.testing.assert_close(alpha_c, alpha_r, atol=atol, rtol=0)
    n_feat = col_c.shape[-1] - (0 if render_mode == "RGB" else 1)
    torch.testing.assert_close(col_c[..., :n_feat], col_r[..., :n_feat], atol=atol, rtol=0)
    if render_mode != "RGB":  # expected depth: metres, compare relative
        torch.testing.assert_close(col_c[..., -1], col_r[..., -1], atol=atol, rtol=1e-5)


@pytest.mark.parametrize("n_cams", [1, 2])
@pytest.mark.parametrize("n", [0, 1, 7, 50])
@pytest.mark.parametrize("dims", [1, 3, 8])
def test_cpu_matches_reference(n_cams: int, n: int, dims: int) -> None:
    scene = random_scene(n, n_cams=n_cams, dims=dims, seed=100 * n + 10 * dims + n_cams)
    backgrounds = torch.rand(n_cams, dims, generator=torch.Generator().manual_seed(n)) if dims != 3 else None
    out_cpu, out_ref = render_both(scene, backgrounds=backgrounds)
    assert out_cpu[0].shape == (n_cams, scene.height, scene.width, dims)
    assert out_cpu[1].shape == (n_cams, scene.height, scene.width, 1)
    assert_images_close(out_cpu, out_ref)


@pytest.mark.parametrize("render_mode", ["RGB", "D", "RGB+ED"])
@pytest.mark.parametrize("with_background", [False, True])
def test_render_modes_match_reference(render_mode: str, with_background: bool) -> None:
    scene = random_scene(60, n_cams=2, dims=3, seed=5)
    backgrounds = torch.tensor([[0.2, 0.4, 0.6], [1.0, 0.0, 0.5]]) if with_background else None
    out_cpu, out_ref = render_both(scene, render_mode=render_mode, backgrounds=backgrounds)
    expected_channels = {"RGB": 3, "D": 1, "RGB+ED": 4}[render_mode]
    assert out_cpu[0].shape[-1] == expected_channels
    assert_images_close(out_cpu, out_ref, render_mode)


def test_expected_depth_channel_is_consistent() -> None:
    scene = random_scene(40, n_cams=2, seed=11)
    bgs = torch.ones(2, 3)
    rgbd, alpha, _ = rasterization(*scene.args(), render_mode="RGB+ED", backgrounds=bgs, backend="cpu")
    depth, _, _ = rasterization(*scene.args(), render_mode="D", backgrounds=bgs, backend="cpu")
    rgb, _, _ = rasterization(*scene.args(), render_mode="RGB", backgrounds=bgs, backend="cpu")
    torch.testing.assert_close(rgbd[..., -1:], depth)
    torch.testing.assert_close(rgbd[..., :3], rgb)
    covered = alpha[..., 0] > 0.5
    assert covered.any()
    z = scene.means[:, 2]
    assert bool((depth[..., 0][covered] >= z.min() - 1.0).all())
    assert bool((depth[..., 0][covered] <= z.max() + 1.0).all())
    assert bool((depth[alpha == 0] == 0).all())  # empty pixels: 0 expected depth, background ignored


def test_edge_cases_match_reference() -> None:
    scene = edge_case_scene(n_cams=2)
    out_cpu, out_ref = render_both(scene, render_mode="RGB+ED", backgrounds=torch.rand(2, 3))
    assert_images_close(out_cpu, out_ref, "RGB+ED")
    radii = out_cpu[2].radii
    assert bool((radii[:, :4] == 0).all())  # behind, before near, off-screen left, off-screen below
    assert bool((radii[0, 4:] > 0).all())


@pytest.mark.parametrize("tile_size", [8, 16])
def test_edge_cases_other_tile_sizes(tile_size: int) -> None:
    scene = edge_case_scene(n_cams=1, dims=2)
    out_cpu, out_ref = render_both(scene, tile_size=tile_size)
    assert_images_close(out_cpu, out_ref)
    assert out_cpu[2].isect_offsets.shape == (1, -(-23 // tile_size), -(-37 // tile_size))


def test_all_behind_camera_renders_background() -> None:
    scene = random_scene(20, n_cams=2, depth=(-9.0, -1.0))
    bgs = torch.tensor([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    (col, alpha, meta), out_ref = render_both(scene, backgrounds=bgs)
    assert bool((meta.radii == 0).all()) and meta.n_isects == 0
    assert bool((alpha == 0).all())
    torch.testing.assert_close(col, bgs[:, None, None, :].expand_as(col))
    assert_images_close((col, alpha, meta), out_ref)


def test_all_off_screen_and_far_plane() -> None:
    scene = random_scene(20, n_cams=1)
    shifted = scene.means + torch.tensor([200.0, 0.0, 0.0])
    col, alpha, meta = rasterization(shifted, *scene.args()[1:], backend="cpu")
    assert bool((meta.radii == 0).all()) and bool((alpha == 0).all()) and bool((col == 0).all())
    col, alpha, meta = rasterization(*scene.args(), far_plane=1.0, backend="cpu")
    assert bool((meta.radii == 0).all()) and bool((alpha == 0).all())


def test_radius_clip_culls_small_gaussians() -> None:
    scene = random_scene(50, seed=3)
    _, _, meta = rasterization(*scene.args(), backend="cpu")
    clip = float(meta.radii[meta.radii > 0].float().median())
    out_cpu, out_ref = render_both(scene, radius_clip=clip)
    assert bool((out_cpu[2].radii[(meta.radii > 0) & (meta.radii <= clip)] == 0).all())
    assert bool((out_cpu[2].radii[meta.radii > clip] == meta.radii[meta.radii > clip]).all())
    assert_images_close(out_cpu, out_ref)


def test_per_camera_colors_and_many_channels() -> None:
    scene = random_scene(30, n_cams=2, dims=3, seed=9)
    colors = torch.rand(2, 30, 65, generator=torch.Generator().manual_seed(1))
    args = list(scene.args())
    args[4] = colors
    col_c, alpha_c, _ = rasterization(*args, backend="cpu")
    col_r, alpha_r, _ = rasterization(*args, backend="reference")
    assert col_c.shape == (2, 23, 37, 65)
    torch.testing.assert_close(col_c, col_r, atol=ATOL, rtol=0)
    torch.testing.assert_close(alpha_c, alpha_r, atol=ATOL, rtol=0)


def test_dense_scene_saturates_and_matches() -> None:
    """Many overlapping opaque Gaussians: pixels stop at T <= 1e-4, like gsplat."""
    scene = random_scene(400, n_cams=1, dims=3, seed=21, scale=(0.2, 0.8))
    scene = type(scene)(**{**scene.__dict__, "opacities": 0.6 + 0.39 * torch.rand(400)})
    out_cpu, out_ref = render_both(scene, render_mode="RGB+ED")
    assert float(out_cpu[1].min()) > 0.99
    assert_images_close(out_cpu, out_ref, "RGB+ED")


def test_float64_matches_reference_tightly() -> None:
    scene = random_scene(50, n_cams=2, dims=4, seed=4, dtype=torch.float64)
    out_cpu, out_ref = render_both(scene, render_mode="RGB+ED", backgrounds=torch.rand(2, 4, dtype=torch.float64))
    assert out_cpu[0].dtype == torch.float64 and out_cpu[1].dtype == torch.float64
    assert_images_close(out_cpu, out_ref, "RGB+ED", atol=1e-10)


def test_result_independent_of_thread_schedule() -> None:
    scene = random_scene(200, n_cams=2, seed=8)
    first = rasterization(*scene.args(), backend="cpu")
    second = rasterization(*scene.args(), backend="cpu")
    assert torch.equal(first[0], second[0]) and torch.equal(first[1], second[1])
