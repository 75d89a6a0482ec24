"""Expected depth from an accumulated depth channel, for every backend in one place.

Every backend composites depth like a colour channel, giving the accumulated depth ``sum(w_i z_i)``
``[C, H, W, 1]`` beside the alpha ``sum(w_i) = 1 - T`` ``[C, H, W, 1]``; :func:`finish_channels` divides
one by the other. gsplat's own ``"ED"`` mode divides by ``max(alpha, 1e-10)`` inside the library; it is
not used. Why: on a GPU the alpha is ``1 - T`` in float32, so for a pixel that a Gaussian barely
touches (``alpha ~ 1e-6``) it carries a rounding error of the order of float32's epsilon (``~1e-7``),
10 % of its value, and the accumulated depth carries an independent one. Their quotient is then off by
metres at such a pixel when compared with the CPU reference. Dividing by
``max(alpha, ED_EPS)`` with ``ED_EPS = 1e-4`` bounds that error to about ``1e-3`` of the depth and blends
the depth of nearly empty pixels towards 0, the depth background.
"""

from __future__ import annotations

import torch
from torch import Tensor

from simsplat_core.render.types import ED_EPS


def finish_channels(render: Tensor, alphas: Tensor, render_mode: str) -> Tensor:
    """``render [C, H, W, X]`` whose last channel is the accumulated depth (modes ``"D"``, ``"RGB+ED"``)
    -> the same with expected depth ``sum(w z) / max(sum(w), ED_EPS)``; ``"RGB"`` passes through.
    ``alphas [C, H, W, 1]``."""
    if render_mode == "RGB":
        return render
    depth = render[..., -1:] / alphas.clamp(min=ED_EPS)  # [C, H, W, 1]
    return torch.cat([render[..., :-1], depth], dim=-1)



__all__ = ["finish_channels"]
