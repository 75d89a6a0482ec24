import numba
import pytest
import torch

from simsplat_core.compute_threads import compute_threads, set_compute_threads


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
