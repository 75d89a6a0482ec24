"""Rendering composed Gaussians: RGB, alpha, expected depth and a per-pixel node id.

**Node id.** A pixel's node is the node whose Gaussians have the largest total compositing weight
``sum_i T_i alpha_i`` there (``-1`` where the pixel's alpha is below 0.5). It is computed exactly by
rendering one-hot node indicators as extra channels: after the colour pass, the nodes with at least one
Gaussian visible in some camera are split into chunks of at most ``id_chunk`` nodes; each chunk is one
rasterization whose channel ``j`` is 1 on Gaussians of the chunk's ``j``-th node and 0 elsewhere (the
other Gaussians still occlude through their alpha). The per-pixel argmax is kept across chunks. Typical
driving scenes have a few dozen visible nodes, i.e. one extra pass. For inference, ``fused_ids`` composites
the indicators of every present node in the colour pass itself (no second projection and sort).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from simsplat_core.render import RasterMeta, rasterization
from simsplat_core.scene.composed import ComposedGaussians

#: Pixels with a rendered alpha below this get node id -1.
NODE_ID_MIN_ALPHA = 0.5
#: Default screen-space low-pass (added to each 2D covariance, pixels^2), gsplat's value.
DEFAULT_EPS2D = 0.3


@dataclass(frozen=True)
class SceneRender:
    """Images of ``C`` cameras.

    Attributes:
        rgb: ``[C, H, W, 3]`` composited colour (background colour blended by the final transmittance).
        alpha: ``[C, H, W, 1]`` accumulated opacity.
        depth: ``[C, H, W, 1]`` expected depth ``sum(w z) / sum(w)`` (0 where nothing was hit).
        node_id: ``[C, H, W]`` int32 node of largest weight, ``-1`` where ``alpha < 0.5``; ``None`` when
            not requested.
        meta: the colour pass's :class:`~simsplat_core.render.RasterMeta` (``means2d`` is in the graph
            when rendered with grad: densification reads its gradient).
        extra: ``[C, H, W, E]`` composited extra per-Gaussian channels when requested (``extra=`` of
            :func:`render_composed`), else ``None``.
    """

    rgb: Tensor
    alpha: Tensor
    depth: Tensor
    node_id: Tensor | None
    meta: RasterMeta | None = None
    extra: Tensor | None = None


def world_to_camera(cam_to_world: Tensor) -> Tensor:
    """``[C, 4, 4]`` OpenCV cam->world -> world->cam (rigid inverse)."""
    rot_t = cam_to_world[:, :3, :3].transpose(1, 2)
    out = torch.zeros_like(cam_to_world)
    out[:, :3, :3] = rot_t
    out[:, :3, 3] = -(rot_t @ cam_to_world[:, :3, 3:4])[..., 0]
    out[:, 3, 3] = 1.0
    return out


def render_composed(  # noqa: PLR0913 -- rasterization's (gsplat's) options, keyword-only
    gs: ComposedGaussians,
    cam_to_world: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    *,
    with_node_ids: bool = True,
    backend: str = "auto",
    background: Tensor | None = None,  # [3]
    id_chunk: int = 32,
    extra: Tensor | None = None,  # [N, E]
    eps2d: float = DEFAULT_EPS2D,
    fused_ids: bool = False,
) -> SceneRender:
    """Rasterize composed Gaussians into ``C`` cameras (differentiable in the colour/depth pass).

    ``extra [N, E]`` per-Gaussian channels are composited in the same pass (background 0) and returned
    as ``SceneRender.extra`` (e.g. an object indicator whose render is the object coverage).
    ``eps2d`` is the rasterizer's screen-space low-pass; a scene must be rendered with the value it was
    trained with (``SceneGraph.eps2d``).

    ``fused_ids`` (inference): the node indicators of every node present are composited as extra channels of
    the colour pass instead of a pass of their own (module docstring) -- the same ids, about 40 % less time
    for a driving scene's couple of dozen nodes, but the colour pass then carries ``K`` more channels (not
    for training).
    """
    device, dtype = gs.means.device, gs.means.dtype
    cam_to_world = torch.as_tensor(cam_to_world, dtype=dtype, device=device)
    Ks = torch.as_tensor(Ks, dtype=dtype, device=device)
    n_cams = cam_to_world.shape[0]
    viewmats = world_to_camera(cam_to_world)
    user_extra = 0 if extra is None else extra.shape[-1]
    present = torch.zeros(0, dtype=torch.int32, device=device)
    if with_node_ids and fused_ids and len(gs):
        present, indicators = node_indicators(gs)  # [K], [N, K]
        extra = indicators if extra is None else torch.cat([extra.to(dtype), indicators], dim=-1)
    n_extra = 0 if extra is None else extra.shape[-1]
    colors = gs.colors if extra is None else torch.cat([gs.colors, extra.to(dtype)], dim=-1)  # [N, 3 + E]
    bgs = None
    if background is not None:
        bg = torch.as_tensor(background, dtype=dtype, device=device).reshape(1, 3)
        bgs = torch.cat([bg, bg.new_zeros((1, n_extra))], dim=-1).expand(n_cams, 3 + n_extra)
    render, alpha, meta = rasterization(gs.means, gs.quats, gs.scales, gs.opacities, colors, viewmats, Ks,
                                        width, height, render_mode="RGB+ED", backgrounds=bgs, backend=backend,
                                        eps2d=eps2d)
    rgb, depth = render[..., :3], render[..., -1:]
    extra_out = render[..., 3:3 + user_extra] if user_extra else None
    node_id = None
    if with_node_ids and fused_ids:
        with torch.no_grad():
            if len(present):
                weights = render[..., 3 + user_extra:3 + n_extra]  # [C, H, W, K]
                best = present[weights.argmax(dim=-1)]
            else:
                best = torch.full(alpha.shape[:-1], -1, dtype=torch.int32, device=device)
            node_id = torch.where(alpha[..., 0].detach() >= NODE_ID_MIN_ALPHA, best, torch.full_like(best, -1))
    elif with_node_ids:
        with torch.no_grad():
            node_id = render_node_ids(gs, viewmats, Ks, width, height, alpha.detach(), meta.radii, backend, id_chunk,
                                      eps2d)
    return SceneRender(rgb=rgb, alpha=alpha, depth=depth, node_id=node_id, meta=meta, extra=extra_out)


@torch.no_grad()
def node_indicators(gs: ComposedGaussians) -> tuple[Tensor, Tensor]:
    """``(nodes [K] int32 ids present, one-hot [N, K])``: each Gaussian's node as an indicator column."""
    nodes, column = torch.unique(gs.node_ids, return_inverse=True)  # [K], [N]
    onehot = torch.zeros((len(gs), nodes.shape[0]), dtype=gs.means.dtype, device=gs.means.device)
    onehot[torch.arange(len(gs), device=gs.means.device), column] = 1.0
    return nodes.to(torch.int32), onehot


@torch.no_grad()
def node_weight_argmax(
    gs: ComposedGaussians,
    nodes: Tensor,  # [K] node ids to consider
    viewmats: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    backend: str = "auto",
    id_chunk: int = 32,
    eps2d: float = DEFAULT_EPS2D,
) -> tuple[Tensor, Tensor | None]:
    """``([C, H, W] int32 node of largest compositing weight among nodes, [C, H, W, 1] alpha)``.

    Renders one-hot node indicators ``id_chunk`` nodes at a time; ``-1`` where none of ``nodes`` has
    weight. The alpha (of all of ``gs``; colours do not change it) comes from the first pass, ``None``
    when ``nodes`` is empty.
    """
    n_cams = viewmats.shape[0]
    device, dtype = gs.means.device, gs.means.dtype
    best_w = torch.zeros((n_cams, height, width), dtype=dtype, device=device)
    best_id = torch.full((n_cams, height, width), -1, dtype=torch.int32, device=device)
    node_ids = gs.node_ids.long()
    nodes = nodes.long()
    column = torch.full((int(max(node_ids.max(), nodes.max())) + 1 if len(nodes) else 1,), -1, dtype=torch.long,
                        device=device)
    alpha = None
    for start in range(0, int(nodes.shape[0]), id_chunk):
        chunk = nodes[start:start + id_chunk]
        column.fill_(-1)
        column[chunk] = torch.arange(chunk.shape[0], device=device)
        col = column[node_ids]  # [N] column of each Gaussian's node in this chunk, -1 outside it
        rows = torch.nonzero(col >= 0)[:, 0]
        onehot = torch.zeros((len(gs), chunk.shape[0]), dtype=dtype, device=device)
        onehot[rows, col[rows]] = 1.0
        weights, chunk_alpha, _ = rasterization(gs.means, gs.quats, gs.scales, gs.opacities, onehot, viewmats, Ks,
                                                width, height, render_mode="RGB", backend=backend, eps2d=eps2d)
        alpha = chunk_alpha if alpha is None else alpha
        w_max, arg = weights.max(dim=-1)  # [C, H, W]
        better = w_max > best_w
        best_w = torch.where(better, w_max, best_w)
        best_id = torch.where(better, chunk[arg].to(torch.int32), best_id)
    return best_id, alpha


@torch.no_grad()
def render_node_ids(
    gs: ComposedGaussians,
    viewmats: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    alpha: Tensor,  # [C, H, W, 1]
    radii: Tensor,  # [C, N]
    backend: str = "auto",
    id_chunk: int = 32,
    eps2d: float = DEFAULT_EPS2D,
) -> Tensor:
    """``[C, H, W]`` int32 node of largest compositing weight per pixel (see the module docstring)."""
    visible = (radii > 0).any(dim=0)  # [N]
    nodes = torch.unique(gs.node_ids[visible]) if len(gs) else gs.node_ids[:0]
    best_id, _ = node_weight_argmax(gs, nodes, viewmats, Ks, width, height, backend, id_chunk, eps2d)
    return torch.where(alpha[..., 0] >= NODE_ID_MIN_ALPHA, best_id, torch.full_like(best_id, -1))
