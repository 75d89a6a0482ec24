"""``GaussianSet``: the raw (pre-activation) parameters of one node's Gaussians, row per Gaussian.

Parameterisation (what the optimiser sees -> what the rasterizer gets):

* ``means [N, 3]``: centres in the node's frame (world for the background, box frame for objects);
* ``log_scales [N, 3]``: ``scale = exp(log_scale)`` metres;
* ``quats [N, 4]``: ``(w, x, y, z)``, unnormalised (normalised on use);
* ``colors [N, 3]``: **logits**, ``rgb = sigmoid(colors)`` in ``(0, 1)``;
* ``opacity_logits [N]``: ``opacity = sigmoid(opacity_logit)``;
* ``features [N, d]`` (optional): free per-Gaussian features (language alignment), no activation;
* ``extras``: node-specific per-Gaussian tensors whose first axis is the Gaussian, e.g. the non-rigid
  deformation ``"offsets" [N, T, 3]``. Densification treats every row tensor alike.

The row operations (:meth:`index`, :meth:`cat`, :meth:`map_rows`) are what densification is built from.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import torch
from torch import Tensor

#: The fixed per-Gaussian tensors, in a stable order (``features`` and ``extras`` follow when present).
CORE_FIELDS: tuple[str, ...] = ("means", "log_scales", "quats", "colors", "opacity_logits")


def logit(p: Tensor, eps: float = 1e-6) -> Tensor:
    """Inverse sigmoid with the argument clamped to ``[eps, 1 - eps]``."""
    p = p.clamp(eps, 1.0 - eps)
    return torch.log(p) - torch.log1p(-p)


@dataclass
class GaussianSet:
    """Row-aligned tensors of ``N`` Gaussians (see the module docstring for the parameterisation)."""

    means: Tensor  # [N, 3]
    log_scales: Tensor  # [N, 3]
    quats: Tensor  # [N, 4]
    colors: Tensor  # [N, 3] logits
    opacity_logits: Tensor  # [N]
    features: Tensor | None = None  # [N, d]
    extras: dict[str, Tensor] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = self.means.shape[0]
        expected = {"means": (n, 3), "log_scales": (n, 3), "quats": (n, 4), "colors": (n, 3), "opacity_logits": (n,)}
        for name, shape in expected.items():
            got = tuple(getattr(self, name).shape)
            if got != shape:
                raise ValueError(f"GaussianSet.{name} must have shape {list(shape)}, got {list(got)}")
        if self.features is not None and (self.features.dim() != 2 or self.features.shape[0] != n):
            raise ValueError(f"GaussianSet.features must be [N={n}, d], got {list(self.features.shape)}")
        for name, tensor in self.extras.items():
            if tensor.shape[0] != n:
                raise ValueError(f"GaussianSet.extras[{name!r}] must have N={n} rows, got {list(tensor.shape)}")

    # ------------------------------------------------------------------ construction
    @classmethod
    def create(cls, means: Tensor, scales: Tensor, rgb: Tensor, opacity: float | Tensor = 0.1,
               quats: Tensor | None = None, features: Tensor | None = None,
               extras: dict[str, Tensor] | None = None) -> GaussianSet:
        """From activated values: ``means [N, 3]``, ``scales [N, 3]`` (or ``[N]``, isotropic) metres,
        ``rgb [N, 3]`` in ``[0, 1]``, ``opacity`` scalar or ``[N]``; identity rotations unless given."""
        n = means.shape[0]
        dtype, device = means.dtype, means.device
        scales = scales if scales.dim() == 2 else scales[:, None].expand(n, 3)
        opacity_t = torch.as_tensor(opacity, dtype=dtype, device=device).expand(n).clone()
        if quats is None:
            quats = torch.zeros((n, 4), dtype=dtype, device=device)
            quats[:, 0] = 1.0
        return cls(means=means.clone(), log_scales=torch.log(scales.clamp(min=1e-8)).to(dtype), quats=quats.clone(),
                   colors=logit(rgb.to(dtype)), opacity_logits=logit(opacity_t), features=features,
                   extras=dict(extras or {}))

    @classmethod
    def empty(cls, dtype: torch.dtype = torch.float32, device: torch.device | str = "cpu",
              extras_shapes: dict[str, tuple[int, ...]] | None = None) -> GaussianSet:
        """A set with no Gaussians; ``extras_shapes`` gives the trailing shape of each extra tensor."""
        z = lambda *s: torch.zeros(s, dtype=dtype, device=device)  # noqa: E731
        extras = {k: z(0, *shape) for k, shape in (extras_shapes or {}).items()}
        return cls(z(0, 3), z(0, 3), z(0, 4), z(0, 3), z(0), None, extras)

    # ------------------------------------------------------------------ views
    def __len__(self) -> int:
        return int(self.means.shape[0])

    @property
    def num(self) -> int:
        return len(self)

    @property
    def scales(self) -> Tensor:
        """``[N, 3]`` activated scales (metres)."""
        return torch.exp(self.log_scales)

    @property
    def rgb(self) -> Tensor:
        """``[N, 3]`` activated colours in ``(0, 1)``."""
        return torch.sigmoid(self.colors)

    @property
    def opacities(self) -> Tensor:
        """``[N]`` activated opacities in ``(0, 1)``."""
        return torch.sigmoid(self.opacity_logits)

    @property
    def unit_quats(self) -> Tensor:
        """``[N, 4]`` normalised quaternions."""
        return torch.nn.functional.normalize(self.quats, dim=-1)

    def named_tensors(self) -> Iterator[tuple[str, Tensor]]:
        """``(name, tensor)`` for every row tensor: core fields, ``features``, then ``extras`` (sorted)."""
        for name in CORE_FIELDS:
            yield name, getattr(self, name)
        if self.features is not None:
            yield "features", self.features
        for name in sorted(self.extras):
            yield name, self.extras[name]

    def get(self, name: str) -> Tensor:
        """Row tensor by name (a core field, ``"features"`` or an extra)."""
        if name in CORE_FIELDS or name == "features":
            value = getattr(self, name)
            if value is None:
                raise KeyError(f"GaussianSet has no {name!r}")
            return value
        return self.extras[name]

    # ------------------------------------------------------------------ row operations
    def map_rows(self, fn: Callable[[str, Tensor], Tensor]) -> GaussianSet:
        """A new set whose every row tensor is ``fn(name, tensor)`` (which must keep rows aligned)."""
        out = {name: fn(name, tensor) for name, tensor in self.named_tensors()}
        return GaussianSet(
            means=out["means"], log_scales=out["log_scales"], quats=out["quats"], colors=out["colors"],
            opacity_logits=out["opacity_logits"], features=out.get("features"),
            extras={k: out[k] for k in self.extras},
        )

    def index(self, rows: Tensor) -> GaussianSet:
        """Rows selected by an index ``[M]`` (int64) or a mask ``[N]`` (bool)."""
        return self.map_rows(lambda _, t: t[rows])

    select = index

    def detach(self) -> GaussianSet:
        return self.map_rows(lambda _, t: t.detach())

    def clone(self) -> GaussianSet:
        return self.map_rows(lambda _, t: t.detach().clone())

    def to(self, device: torch.device | str | None = None, dtype: torch.dtype | None = None) -> GaussianSet:
        return self.map_rows(lambda _, t: t.to(device=device, dtype=dtype if t.is_floating_point() else None))

    def requires_grad_(self, flag: bool = True) -> GaussianSet:
        """Make every row tensor a leaf requiring grad (in place on the tensors); returns self."""
        for _, tensor in self.named_tensors():
            tensor.requires_grad_(flag)
        return self

    @staticmethod
    def cat(sets: list[GaussianSet]) -> GaussianSet:
        """Concatenate sets with the same optional tensors along the Gaussian axis."""
        if not sets:
            raise ValueError("GaussianSet.cat needs at least one set")
        names = [name for name, _ in sets[0].named_tensors()]
        for s in sets[1:]:
            if [name for name, _ in s.named_tensors()] != names:
                raise ValueError("GaussianSet.cat: sets have different tensors")
        parts = {name: torch.cat([s.get(name) for s in sets], dim=0) for name in names}
        return GaussianSet(
            means=parts["means"], log_scales=parts["log_scales"], quats=parts["quats"], colors=parts["colors"],
            opacity_logits=parts["opacity_logits"], features=parts.get("features"),
            extras={k: parts[k] for k in sets[0].extras},
        )

