"""``ComposedGaussians``: the world-space Gaussians of a scene graph at one time (``SceneGraph.at(t)``)."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor


@dataclass(frozen=True)
class ComposedGaussians:
    """Activated world-space Gaussians of every node present at time ``t``, node blocks in node order.

    Attributes:
        t: the (fractional) frame index they were composed for.
        means: ``[N, 3]`` world-space centres.
        quats: ``[N, 4]`` unit quaternions ``(w, x, y, z)`` (node rotation ⊗ local rotation).
        scales: ``[N, 3]`` metres.
        opacities: ``[N]`` in ``(0, 1)``.
        colors: ``[N, 3]`` RGB in ``(0, 1)``.
        features: ``[N, d]`` or ``None`` (zeros for nodes without features when others have them).
        node_ids: ``[N]`` int32 node of each Gaussian.
        gaussian_ids: ``[N]`` int64 row of each Gaussian in the graph's canonical concatenation of all
            nodes' Gaussians (``SceneGraph.node_offsets()``), for mapping render statistics back.
        node_slices: ``((node_id, start, stop), ...)`` the contiguous block of each included node.
    """

    t: float
    means: Tensor
    quats: Tensor
    scales: Tensor
    opacities: Tensor
    colors: Tensor
    features: Tensor | None
    node_ids: Tensor
    gaussian_ids: Tensor
    node_slices: tuple[tuple[int, int, int], ...]

    def __len__(self) -> int:
        return int(self.means.shape[0])

    @property
    def included_nodes(self) -> tuple[int, ...]:
        return tuple(nid for nid, _, _ in self.node_slices)

    def node_mask(self, node_id: int) -> Tensor:
        """``[N]`` bool rows of ``node_id``."""
        return self.node_ids == node_id

    def detach(self) -> ComposedGaussians:
        features = None if self.features is None else self.features.detach()
        return ComposedGaussians(self.t, self.means.detach(), self.quats.detach(), self.scales.detach(),
                                 self.opacities.detach(), self.colors.detach(), features, self.node_ids,
                                 self.gaussian_ids, self.node_slices)

    @property
    def device(self) -> torch.device:
        return self.means.device
