"""Records shared by the rasterizer backends: the projection result, the tile intersections and the
per-call metadata returned by :func:`simsplat_core.render.rasterization`.

Constants here fix the compositing rules every backend follows (gsplat 1.x "classic" mode).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from torch import Tensor

RenderMode = Literal["RGB", "D", "RGB+ED"]
Backend = Literal["auto", "cpu", "gsplat", "reference"]

RENDER_MODES: tuple[str, ...] = ("RGB", "D", "RGB+ED")
BACKENDS: tuple[str, ...] = ("auto", "cpu", "gsplat", "reference")

#: A Gaussian contributes to a pixel only when its alpha reaches this value (gsplat's ALPHA_THRESHOLD).
ALPHA_THRESHOLD = 1.0 / 255.0
#: Per-Gaussian alpha is clamped to this value.
MAX_ALPHA = 0.999
#: A pixel stops compositing when the transmittance would fall to this value or below; the Gaussian
#: that would cross it is excluded (gsplat: ``next_T <= 1e-4`` -> done).
TRANSMITTANCE_MIN = 1e-4
#: The camera-space x/y used in the projection Jacobian are clamped to the field of view widened by
#: this fraction of tan(fov/2) on each side (gsplat: 0.3, i.e. 1.3x tan(fov/2) for a centred camera).
FOV_MARGIN = 0.3
#: Expected depth is ``sum(w z) / max(sum(w), ED_EPS)`` for every backend (see ``render.depth``: a
#: smaller floor turns float32 rounding of a nearly empty pixel's alpha into metres of depth).
ED_EPS = 1e-4


@dataclass(frozen=True)
class Projection:
    """Per-camera 2D Gaussians from the EWA projection (all ``[C, N, ...]``; culled entries have radius 0).

    Attributes:
        means2d: ``[C, N, 2]`` pixel coordinates of the projected means (differentiable).
        conics: ``[C, N, 3]`` upper triangle ``(a, b, c)`` of the inverse 2D covariance (differentiable).
        depths: ``[C, N]`` camera-space z (differentiable).
        radii: ``[C, N]`` int32 screen-space radius in pixels, ``ceil(3 sqrt(lambda_max))``; 0 = culled.
    """

    means2d: Tensor
    conics: Tensor
    depths: Tensor
    radii: Tensor


@dataclass(frozen=True)
class TileIntersections:
    """Gaussian-tile intersections sorted by (camera, tile, depth), like gsplat's ``isect_tiles``.

    Attributes:
        tiles_per_gauss: ``[C, N]`` int32 number of tiles each Gaussian touches (0 when culled).
        isect_offsets: ``[C, tile_height, tile_width]`` int64 start of each tile's run in ``flatten_ids``;
            the run ends at the next tile's offset (or ``n_isects`` for the last tile).
        flatten_ids: ``[M]`` int64 index ``c * N + n`` of the Gaussian of each intersection.
        tile_size, tile_width, tile_height: the tile grid (``tile_width = ceil(width / tile_size)``).
    """

    tiles_per_gauss: Tensor
    isect_offsets: Tensor
    flatten_ids: Tensor
    tile_size: int
    tile_width: int
    tile_height: int

    @property
    def n_isects(self) -> int:
        return int(self.flatten_ids.shape[0])


@dataclass(frozen=True)
class RasterMeta:
    """What :func:`rasterization` knows besides the images (gsplat's ``meta`` dict, as a record).

    Call ``meta.means2d.retain_grad()`` before ``backward()`` to read the screen-space gradient that
    densification uses (``meta.means2d.grad``, ``[C, N, 2]``, pixels).

    Attributes:
        radii: ``[C, N]`` int32 pixel radius; 0 for Gaussians culled in that camera.
        means2d: ``[C, N, 2]`` projected means (a non-leaf tensor of the autograd graph).
        depths: ``[C, N]`` camera-space depth.
        conics: ``[C, N, 3]`` inverse 2D covariances (upper triangle).
        opacities: ``[C, N]`` per-camera opacities used for compositing.
        n_cameras, width, height: the render target.
        tile_size, tile_width, tile_height: the tile grid.
        backend: the backend that produced the render ("cpu", "reference" or "gsplat").
        render_mode: the render mode.
        tiles_per_gauss: ``[C, N]`` tiles touched per Gaussian (None for the reference backend).
        isect_offsets: ``[C, tile_height, tile_width]`` (None for the reference backend).
        flatten_ids: ``[M]`` (None for the reference backend).
    """

    radii: Tensor
    means2d: Tensor
    depths: Tensor
    conics: Tensor
    opacities: Tensor
    n_cameras: int
    width: int
    height: int
    tile_size: int
    tile_width: int
    tile_height: int
    backend: str
    render_mode: str
    tiles_per_gauss: Tensor | None = None
    isect_offsets: Tensor | None = None
    flatten_ids: Tensor | None = None

    @property
    def n_isects(self) -> int:
        """Number of Gaussian-tile intersections (0 when the backend does not bin)."""
        return 0 if self.flatten_ids is None else int(self.flatten_ids.shape[0])

    @property
    def visible(self) -> Tensor:
        """``[C, N]`` bool: the Gaussian survived culling in that camera."""
        return self.radii > 0
