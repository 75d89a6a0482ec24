"""ReconstructionConfig validation names the offending field."""

from __future__ import annotations

import dataclasses

import pytest

from simsplat_core.scene import (
    ConfigError,
    DensifyConfig,
    InitConfig,
    LearningRates,
    LossWeights,
    ParamLRs,
    ReconstructionConfig,
)


def test_defaults_are_valid_and_frozen() -> None:
    cfg = ReconstructionConfig()
    assert cfg.loss.dssim == 0.2 and cfg.backend == "auto" and cfg.device == "auto"
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.iterations = 5  # type: ignore[misc]


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"iterations": 0}, "ReconstructionConfig.iterations"),
        ({"iterations": 2.5}, "ReconstructionConfig.iterations"),
        ({"cameras_per_step": 0}, "ReconstructionConfig.cameras_per_step"),
        ({"backend": "vulkan"}, "ReconstructionConfig.backend"),
        ({"device": "tpu"}, "ReconstructionConfig.device"),
        ({"eval_every": -1}, "ReconstructionConfig.eval_every"),
        ({"loss": LossWeights(dssim=1.5)}, "ReconstructionConfig.loss.dssim"),
        ({"loss": LossWeights(depth=-1.0)}, "ReconstructionConfig.loss.depth"),
        ({"densify": DensifyConfig(refine_every=0)}, "ReconstructionConfig.densify.refine_every"),
        ({"densify": DensifyConfig(refine_stop_fraction=2.0)}, "ReconstructionConfig.densify.refine_stop_fraction"),
        ({"init": InitConfig(init_opacity=1.0)}, "ReconstructionConfig.init.init_opacity"),
        ({"init": InitConfig(shadow_spacing=-0.1)}, "ReconstructionConfig.init.shadow_spacing"),
        ({"init": InitConfig(shadow_opacity=0.0)}, "ReconstructionConfig.init.shadow_opacity"),
        ({"init": InitConfig(object_voxel_min=1.0, object_voxel_max=0.5)},
         "ReconstructionConfig.init.object_voxel_max"),
        ({"lr": LearningRates(rigid=ParamLRs(colors=-1.0))}, "ReconstructionConfig.lr.rigid.colors"),
        ({"lr": LearningRates(means_final_factor=0.0)}, "ReconstructionConfig.lr.means_final_factor"),
    ],
)
def test_invalid_values_name_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(ConfigError) as info:
        ReconstructionConfig(**kwargs)
    assert field in str(info.value)
    assert isinstance(info.value, ValueError)
