"""The labeller and the aligner on the real Argoverse 2 sample (skipped when ../shared/data is absent)."""

from __future__ import annotations

import collections

import numpy as np
import pytest

from simsplat_core.data.av2 import load_av2_log
from simsplat_core.language.motion_labels import label_log
from simsplat_core.scenario import vocabulary as voc

AV2_LOG = "av2/sensor-log-7fab2350"


@pytest.fixture(scope="module")
def av2_log(shared_data):
    return load_av2_log(shared_data / AV2_LOG)


@pytest.mark.shared_data
def test_av2_label_distribution_is_plausible(av2_log) -> None:
    labels = label_log(av2_log)
    movable = [o for o in av2_log.objects if o.category in ("vehicle", "pedestrian", "cyclist", "other")]
    assert len(labels) == len(movable)
    motion = collections.Counter(lb.motion for lb in labels.values())
    # a city street: most vehicles are parked or waiting, pedestrians stand or walk on sidewalks
    assert motion[voc.PARKED] + motion[voc.STOPPED] > len(labels) / 3
    assert motion[voc.WALKING_ALONG] >= 3 and motion[voc.STANDING] >= 3
    peds = [lb for lb in labels.values() if lb.kind == "pedestrian"]
    assert sum(lb.context == voc.ON_THE_SIDEWALK for lb in peds) >= 0.8 * len(peds)


@pytest.mark.shared_data
def test_aligner_features_on_av2(aligner, av2_log) -> None:
    feats = aligner.features(av2_log)
    assert len(feats) == len(label_log(av2_log))
    assert all(np.isfinite(f.f_mot).all() and np.isfinite(f.f_loc).all() for f in feats.values())
