"""A ``torch.utils.data.Dataset`` of agent-centric samples over the Parquet dataset (``parquet_tables`` layout).

The tables of the split are read once with pyarrow (no pandas) into per-scenario arrays (``dataset_arrays``); a
sample is one (scenario, agent valid at the scenario's current step), sorted by scenario id then track id, and is
built on access, deterministically, in the agent's frame (``agent_samples``: every key with its shape and units).

Usage::

    from torch.utils.data import DataLoader
    from simsplat_core.export.torch_dataset import AgentCentricDataset, agent_to_world, collate_agent_samples

    data = AgentCentricDataset("datasets/mined/parquet", split="train", agents="to_predict")
    loader = DataLoader(data, batch_size=32, shuffle=True, collate_fn=collate_agent_samples, num_workers=2)
    for batch in loader:
        history, map_polylines = batch["history"], batch["map_polylines"]   # [B, H, 10], [B, M, P, 12]
        predicted = model(batch)                                             # [B, Fu, 2] in each agent's frame
        loss = ((predicted - batch["future"][..., :2]).norm(dim=-1) * batch["future_valid"]).mean()
        world_xy = agent_to_world(predicted, batch["origin"])                # [B, Fu, 2] world frame
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
import torch
from torch.utils.data import Dataset

from simsplat_core.export.agent_samples import SampleConfig, agent_sample
from simsplat_core.export.dataset_arrays import ScenarioArrays, load_scenario_arrays

logger = logging.getLogger(__name__)

AgentSelection = Literal["to_predict", "of_interest", "all_valid"]
#: Sample keys whose first dimension varies between samples (``N`` neighbours, ``M`` polylines), padded by
#: :func:`collate_agent_samples`, with the value padding takes.
PADDED_KEYS: dict[str, float] = {
    "neighbors": 0.0, "neighbors_valid": False, "neighbor_type": -1, "neighbor_track_id": -1,
    "map_polylines": 0.0, "map_valid": False, "map_kind": -1, "map_feature_id": -1, "map_signal_state": -1,
}


class AgentCentricDataset(Dataset[dict[str, Any]]):
    """Agent-centric samples of one split (module docstring).

    Args:
        root: the ``<dataset>/parquet`` folder.
        split: the split to read (``None``: every split).
        history_steps, future_steps, map_radius_m, max_polylines, points_per_polyline, max_neighbors: the
            ``agent_samples.SampleConfig``.
        agents: which agents give samples, each valid at its scenario's current step: ``"to_predict"`` (the
            scenario's tracks to predict), ``"of_interest"`` (its objects of interest) or ``"all_valid"``.
    """

    def __init__(self, root: str | Path, split: str | None = "train", *, history_steps: int = 11,  # noqa: PLR0913
                 future_steps: int = 80, map_radius_m: float = 50.0, max_polylines: int = 64,
                 points_per_polyline: int = 20, max_neighbors: int = 32, agents: AgentSelection = "to_predict"
                 ) -> None:
        if agents not in ("to_predict", "of_interest", "all_valid"):
            raise ValueError(f"agents must be 'to_predict', 'of_interest' or 'all_valid', got {agents!r}")
        self.config = SampleConfig(history_steps, future_steps, map_radius_m, max_polylines, points_per_polyline,
                                   max_neighbors)
        self.scenarios: tuple[ScenarioArrays, ...] = load_scenario_arrays(root, split)
        self.index: tuple[tuple[int, int], ...] = tuple(
            (k, int(row)) for k, scene in enumerate(self.scenarios) for row in _sample_rows(scene, agents))
        logger.info("%d %s samples from %d scenarios", len(self.index), agents, len(self.scenarios))

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, i: int) -> dict[str, Any]:
        scenario, row = self.index[i]
        sample = agent_sample(self.scenarios[scenario], row, self.config)
        return {key: value if isinstance(value, str) else torch.from_numpy(np.asarray(value))
                for key, value in sample.items()}


def _sample_rows(scene: ScenarioArrays, agents: AgentSelection) -> np.ndarray:
    """Track rows of ``scene`` that give samples (in track id order)."""
    rows = scene.valid[:, scene.current_time_index]
    if agents == "to_predict":
        rows = rows & scene.to_predict
    elif agents == "of_interest":
        rows = rows & scene.of_interest
    return np.flatnonzero(rows)


def collate_agent_samples(batch: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Stack samples into a batch of ``B``.

    Fixed-shape entries are stacked (``history`` -> ``[B, H, 10]``, ``origin`` -> ``[B, 4]``, ``track_id`` ->
    ``[B]``); the variable ones (:data:`PADDED_KEYS`) are padded along their first dimension to the batch's largest
    (``neighbors`` -> ``[B, N, H, 10]``, ``map_polylines`` -> ``[B, M, P, 12]``) with ``False`` / 0 / -1, and
    ``neighbors_mask`` ``[B, N]`` and ``map_mask`` ``[B, M]`` say which entries are real. ``scenario_id`` becomes a
    list of ``B`` strings.
    """
    if not batch:
        raise ValueError("cannot collate an empty batch")
    out: dict[str, Any] = {}
    for key in batch[0]:
        values = [sample[key] for sample in batch]
        if isinstance(values[0], str):
            out[key] = list(values)
        elif key in PADDED_KEYS:
            out[key] = _pad_first(values, PADDED_KEYS[key])
        else:
            out[key] = torch.stack(values)
    for mask, key in (("neighbors_mask", "neighbor_track_id"), ("map_mask", "map_feature_id")):
        if key in out:
            out[mask] = _pad_first([torch.ones(len(sample[key]), dtype=torch.bool) for sample in batch], False)
    return out


def _pad_first(values: list[torch.Tensor], fill: float) -> torch.Tensor:
    """``B`` tensors ``[n_i, ...]`` -> ``[B, max n_i, ...]``, the rest filled with ``fill``."""
    longest = max(len(v) for v in values)
    out = torch.full((len(values), longest, *values[0].shape[1:]), fill, dtype=values[0].dtype)
    for b, value in enumerate(values):
        out[b, :len(value)] = value
    return out


def agent_to_world(xy: torch.Tensor, origin: torch.Tensor) -> torch.Tensor:
    """Agent-frame positions back to world x, y.

    Args:
        xy: ``[B, ..., 2]`` positions in each sample's agent frame (metres).
        origin: ``[B, 4]`` the samples' ``origin`` (world x, y, z, heading).

    Returns:
        ``[B, ..., 2]`` world positions (metres), in ``origin``'s dtype.
    """
    origin = origin.reshape(origin.shape[0], *([1] * (xy.dim() - 2)), origin.shape[-1])
    c, s = torch.cos(origin[..., 3]), torch.sin(origin[..., 3])
    x, y = xy[..., 0].to(origin.dtype), xy[..., 1].to(origin.dtype)
    return torch.stack([origin[..., 0] + c * x - s * y, origin[..., 1] + s * x + c * y], dim=-1)
