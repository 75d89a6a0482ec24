"""API contract: shapes, metadata, backend selection, devices, the gsplat mapping, layering."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import types

import pytest
import torch

from simsplat_core.render import RasterMeta, gsplat_backend, rasterization, select_backend

from .scenes import random_scene

DEVICES = ["cpu"] + (["cuda"] if torch.cuda.is_available() else [])


def test_meta_contents() -> None:
    scene = random_scene(25, n_cams=2, dims=4, seed=6)
    colors, alphas, meta = rasterization(*scene.args(), render_mode="RGB+ED", backend="cpu")
    assert isinstance(meta, RasterMeta)
    assert colors.shape == (2, 23, 37, 5) and alphas.shape == (2, 23, 37, 1)
    assert meta.radii.shape == (2, 25) and meta.radii.dtype == torch.int32
    assert meta.means2d.shape == (2, 25, 2) and meta.conics.shape == (2, 25, 3)
    assert meta.depths.shape == (2, 25) and meta.opacities.shape == (2, 25)
    assert (meta.n_cameras, meta.width, meta.height, meta.tile_size) == (2, 37, 23, 16)
    assert (meta.tile_width, meta.tile_height) == (3, 2)
    assert meta.backend == "cpu" and meta.render_mode == "RGB+ED"
    assert meta.n_isects == int(meta.tiles_per_gauss.sum()) > 0
    assert bool((meta.tiles_per_gauss[meta.radii == 0] == 0).all())
    assert bool((meta.means2d[meta.radii == 0] == 0).all()) and bool((meta.conics[meta.radii == 0] == 0).all())
    with pytest.raises(dataclasses.FrozenInstanceError):
        meta.width = 3  # type: ignore[misc]
    _, _, ref_meta = rasterization(*scene.args(), backend="reference")
    assert ref_meta.backend == "reference" and ref_meta.flatten_ids is None and ref_meta.n_isects == 0
    torch.testing.assert_close(ref_meta.means2d, meta.means2d)


def test_backend_selection_and_validation() -> None:
    cpu = torch.device("cpu")
    assert select_backend("auto", cpu) == "cpu"
    assert select_backend("reference", cpu) == "reference"
    with pytest.raises(ValueError, match="CUDA"):
        select_backend("gsplat", cpu)
    with pytest.raises(ValueError, match="unknown backend"):
        select_backend("vulkan", cpu)
    scene = random_scene(5)
    _, _, meta = rasterization(*scene.args())
    assert meta.backend == "cpu"
    with pytest.raises(ValueError, match="render_mode"):
        rasterization(*scene.args(), render_mode="RGB+D")
    with pytest.raises(ValueError, match="quats"):
        rasterization(scene.means, scene.quats[:, :3], *scene.args()[2:])
    with pytest.raises(ValueError, match="colors"):
        rasterization(*scene.args()[:4], torch.rand(4, 3), *scene.args()[5:])
    with pytest.raises(ValueError, match="backgrounds"):
        rasterization(*scene.args(), backgrounds=torch.rand(1, 4))


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("backend", ["cpu", "reference"])
def test_outputs_follow_input_device(device: str, backend: str) -> None:
    scene = random_scene(10, n_cams=2, seed=1)
    args = [a.to(device) if isinstance(a, torch.Tensor) else a for a in scene.args()]
    colors, alphas, meta = rasterization(*args, backend=backend, render_mode="RGB+ED",
                                         backgrounds=torch.rand(2, 3, device=device))
    for t in (colors, alphas, meta.radii, meta.means2d, meta.depths, meta.conics):
        assert t.device.type == device


def test_gsplat_mapping_with_stub(monkeypatch: pytest.MonkeyPatch) -> None:
    """The gsplat backend's argument/output mapping, checked against a stub module (no GPU here)."""
    calls = {}

    def fake_rasterization(means, quats, scales, opacities, colors, viewmats, Ks, width, height, **kwargs):
        calls.update(kwargs)
        n_cams, n = viewmats.shape[0], means.shape[0]
        radii = torch.tensor([[[3, 4], [0, 0], [2, 5]]] * n_cams, dtype=torch.int32)[:, :n]
        info = {"radii": radii, "means2d": torch.zeros(n_cams, n, 2), "depths": torch.ones(n_cams, n),
                "conics": torch.ones(n_cams, n, 3), "opacities": opacities.expand(n_cams, n), "tile_width": 3,
                "tile_height": 2, "flatten_ids": torch.arange(4), "isect_offsets": torch.zeros(n_cams, 2, 3)}
        return torch.zeros(n_cams, height, width, 1), torch.zeros(n_cams, height, width, 1), info

    monkeypatch.setitem(sys.modules, "gsplat", types.SimpleNamespace(rasterization=fake_rasterization))
    scene = random_scene(3, n_cams=2)
    _, _, meta = gsplat_backend.rasterize_gsplat(*scene.args(), near_plane=0.1, far_plane=50.0, render_mode="D",
                                                 backgrounds=None, tile_size=16, eps2d=0.3, radius_clip=0.5)
    assert calls["render_mode"] == "D" and calls["packed"] is False and calls["rasterize_mode"] == "classic"
    assert (calls["near_plane"], calls["far_plane"], calls["radius_clip"]) == (0.1, 50.0, 0.5)
    assert meta.radii.tolist() == [[4, 0, 5], [4, 0, 5]] and meta.backend == "gsplat" and meta.n_isects == 4


def test_render_package_is_framework_free() -> None:
    code = (
        "import sys, simsplat_core.render; "
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('prefect', 'ray', 'storage', 'gsplat')); "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
