import numba
import numpy as np
import pytest
import torch

from simsplat_core.compute_threads import compute_threads, compute_threads_limited, set_compute_threads
from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder


def test_sets_torch_and_numba_and_returns_previous():
    before = compute_threads()
    try:
        previous = set_compute_threads(1)
        assert previous == before
        assert compute_threads().torch == 1 and torch.get_num_threads() == 1
        assert numba.get_num_threads() == 1
    finally:
        set_compute_threads(before.torch)
    assert compute_threads().torch == before.torch


def test_numba_is_capped_at_its_launch_maximum():
    before = compute_threads()
    try:
        set_compute_threads(numba.config.NUMBA_NUM_THREADS + 3)
        assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS
    finally:
        set_compute_threads(before.torch)


@pytest.mark.parametrize("bad", [0, -1, 1.5, "2"])
def test_rejects_bad_counts(bad):
    with pytest.raises(ValueError, match="count must be a positive int"):
        set_compute_threads(bad)


def test_limited_restores_the_previous_counts_also_on_error():
    before = compute_threads()
    target = 1 if before.torch != 1 else 2
    with compute_threads_limited(target) as inside:
        assert inside.torch == target and torch.get_num_threads() == target
    assert compute_threads() == before
    with pytest.raises(RuntimeError, match="boom"):
        with compute_threads_limited(target):
            raise RuntimeError("boom")
    assert compute_threads() == before
    with compute_threads_limited(None) as inside:
        assert inside == before
    with pytest.raises(ValueError, match="count must be a positive int"):
        with compute_threads_limited(0):
            pass
    assert compute_threads() == before


def test_autoencoder_fit_leaves_the_thread_setting_alone():
    before = compute_threads()
    FeatureAutoencoder.fit(np.random.default_rng(0).normal(size=(6, 16)).astype(np.float32), None,
                           AutoencoderConfig(latent_dim=3, steps=2, threads=1 if before.torch != 1 else 2))
    assert compute_threads() == before
