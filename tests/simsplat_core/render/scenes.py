"""Small random Gaussian scenes for the rasterizer tests."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import torch
from torch import Tensor


@dataclass(frozen=True)
class Scene:
    means: Tensor  # [N, 3]
    quats: Tensor  # [N, 4]
    scales: Tensor  # [N, 3]
    opacities: Tensor  # [N]
    colors: Tensor  # [N, D]
    viewmats: Tensor  # [C, 4, 4]
    Ks: Tensor  # [C, 3, 3]
    width: int
    height: int

    def args(self) -> tuple:
        return (self.means, self.quats, self.scales, self.opacities, self.colors, self.viewmats, self.Ks,
                self.width, self.height)

    def with_grad(self) -> Scene:
        """Copy whose Gaussian parameters are fresh leaves requiring grad."""
        leaf = lambda t: t.detach().clone().requires_grad_(True)  # noqa: E731
        return replace(self, means=leaf(self.means), quats=leaf(self.quats), scales=leaf(self.scales),
                       opacities=leaf(self.opacities), colors=leaf(self.colors))

    def params(self) -> dict[str, Tensor]:
        return {"means": self.means, "quats": self.quats, "scales": self.scales, "opacities": self.opacities,
                "colors": self.colors}


def cameras(n_cams: int, width: int, height: int, dtype: torch.dtype = torch.float32) -> tuple[Tensor, Tensor]:
    """``n_cams`` OpenCV cameras near the origin looking down +z, slightly yawed and shifted."""
    viewmats = []
    for c in range(n_cams):
        yaw = math.radians(8.0 * c)
        rot = torch.tensor([[math.cos(yaw), 0.0, -math.sin(yaw)], [0.0, 1.0, 0.0],
                            [math.sin(yaw), 0.0, math.cos(yaw)]], dtype=dtype)
        vm = torch.eye(4, dtype=dtype)
        vm[:3, :3] = rot
        vm[:3, 3] = torch.tensor([0.3 * c, -0.1 * c, 0.0], dtype=dtype)
        viewmats.append(vm)
    focal = 0.9 * width
    K = torch.tensor([[focal, 0.0, 0.5 * width + 0.7], [0.0, focal * 1.05, 0.5 * height - 0.4], [0.0, 0.0, 1.0]],
                     dtype=dtype)
    return torch.stack(viewmats), K.repeat(n_cams, 1, 1)


def random_scene(
    n: int,
    n_cams: int = 1,
    dims: int = 3,
    width: int = 37,
    height: int = 23,
    seed: int = 0,
    dtype: torch.dtype = torch.float32,
    depth: tuple[float, float] = (2.0, 8.0),
    scale: tuple[float, float] = (0.03, 0.6),
) -> Scene:
    """``n`` Gaussians spread over the view frustum (a few wander outside it)."""
    g = torch.Generator().manual_seed(seed)
    rand = lambda *shape: torch.rand(*shape, generator=g, dtype=dtype)  # noqa: E731
    z = depth[0] + (depth[1] - depth[0]) * rand(n)
    x = (rand(n) * 2.0 - 1.0) * 0.75 * z * width / (0.9 * width) * 0.6
    y = (rand(n) * 2.0 - 1.0) * 0.75 * z * height / (0.9 * width) * 0.6
    means = torch.stack([x, y, z], dim=-1)
    quats = torch.randn(n, 4, generator=g, dtype=dtype)
    log_lo, log_hi = math.log(scale[0]), math.log(scale[1])
    scales = torch.exp(log_lo + (log_hi - log_lo) * rand(n, 3))
    opacities = 0.05 + 0.9 * rand(n)
    colors = rand(n, dims)
    viewmats, Ks = cameras(n_cams, width, height, dtype)
    return Scene(means, quats, scales, opacities, colors, viewmats, Ks, width, height)


def edge_case_scene(n_cams: int = 2, dims: int = 3, width: int = 37, height: int = 23,
                    dtype: torch.dtype = torch.float32) -> Scene:
    """Hand-placed Gaussians: behind the camera, before the near plane, off-screen, straddling tile
    borders (x = 16, 32; y = 16), huge and tiny, nearly transparent and nearly opaque."""
    focal = 0.9 * width
    cx, cy = 0.5 * width + 0.7, 0.5 * height - 0.4

    def at(px: float, py: float, z: float) -> list[float]:
        return [(px - cx) * z / focal, (py - cy) * z / (focal * 1.05), z]

    rows = [  # (pixel x, pixel y, depth, scale, opacity)
        (10.0, 10.0, -3.0, 0.2, 0.9),  # behind the camera
        (10.0, 10.0, 0.005, 0.01, 0.9),  # in front of the near plane
        (-60.0, 10.0, 4.0, 0.05, 0.9),  # off-screen left
        (18.0, 80.0, 4.0, 0.05, 0.9),  # off-screen below
        (16.0, 16.0, 3.0, 0.08, 0.8),  # corner of four tiles
        (32.0, 5.0, 5.0, 0.1, 0.7),  # vertical tile border
        (8.0, 16.0, 6.0, 0.12, 0.6),  # horizontal tile border
        (18.0, 11.0, 7.0, 3.0, 0.5),  # huge
        (25.0, 7.0, 3.5, 0.001, 0.95),  # tiny (eps2d dominated)
        (12.0, 18.0, 2.5, 0.3, 0.02),  # nearly transparent
        (30.0, 18.0, 2.0, 0.25, 0.999),  # nearly opaque
        (36.5, 22.5, 4.0, 0.15, 0.8),  # last pixel, partially off-screen
        (20.0, 12.0, 2.2, 0.4, 0.99),  # big and opaque in front (pixels terminate)
        (20.5, 12.5, 2.3, 0.35, 0.99),
        (19.0, 11.0, 2.4, 0.45, 0.99),
    ]
    means = torch.tensor([at(px, py, z) for px, py, z, _, _ in rows], dtype=dtype)
    n = len(rows)
    g = torch.Generator().manual_seed(7)
    scales = torch.tensor([[s, 0.7 * s, 1.3 * s] for _, _, _, s, _ in rows], dtype=dtype)
    opacities = torch.tensor([o for *_, o in rows], dtype=dtype)
    quats = torch.randn(n, 4, generator=g, dtype=dtype)
    colors = torch.rand(n, dims, generator=g, dtype=dtype)
    viewmats, Ks = cameras(n_cams, width, height, dtype)
    return Scene(means, quats, scales, opacities, colors, viewmats, Ks, width, height)
