"""Differentiable Gaussian rasterization (gsplat's functional API) with CPU, reference and gsplat backends.

    from simsplat_core.render import rasterization
    colors, alphas, meta = rasterization(means, quats, scales, opacities, colors, viewmats, Ks, W, H)

Modules: ``api`` (entry point), ``projection`` (EWA projection), ``binning`` (tile intersections),
``cpu_kernels`` (numba compositing forward/backward), ``cpu_backend`` (autograd wrapper),
``reference`` (dense pure-torch reference), ``gsplat_backend`` (CUDA via gsplat), ``types`` (records).
"""

from simsplat_core.render.api import rasterization, select_backend
from simsplat_core.render.binning import isect_tiles, tile_grid
from simsplat_core.render.cpu_backend import rasterize_to_pixels
from simsplat_core.render.projection import project_gaussians
from simsplat_core.render.types import Projection, RasterMeta, TileIntersections

__all__ = [
    "Projection",
    "RasterMeta",
    "TileIntersections",
    "isect_tiles",
    "project_gaussians",
    "rasterization",
    "rasterize_to_pixels",
    "select_backend",
    "tile_grid",
]
