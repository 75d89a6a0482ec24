"""MP4 encoding of picture sequences (``storage.pictures``): bad input is refused with a clear message."""

from __future__ import annotations

import numpy as np
import pytest

from storage.pictures import encode_mp4


def test_mp4_rejects_no_frames_and_float_frames() -> None:
    with pytest.raises(ValueError, match="no frames"):
        encode_mp4([])
    with pytest.raises(ValueError, match="frame 0 is"):
        encode_mp4([np.zeros((16, 16, 3), np.float32)])
