"""RefAV's scenario-mining metrics (Argoverse 2 scenario mining): balanced accuracies of per-frame and per-log
predictions.

Balanced accuracy = (true-positive rate + true-negative rate) / 2. A rate whose class is empty (no positive
frames at all, e.g. a negative query) is left out and the other rate alone is returned; with both empty it is
``nan``.
"""

from __future__ import annotations

import numpy as np


def balanced_accuracy(truth: np.ndarray, predicted: np.ndarray) -> float:
    """Balanced accuracy of bool ``predicted`` against bool ``truth`` (same shape, flattened)."""
    t = np.asarray(truth, dtype=bool).ravel()
    p = np.asarray(predicted, dtype=bool).ravel()
    if t.shape != p.shape:
        raise ValueError(f"balanced_accuracy: truth has {t.size} entries, predicted {p.size}")
    rates = []
    if t.any():
        rates.append(float(np.mean(p[t])))
    if (~t).any():
        rates.append(float(np.mean(~p[~t])))
    return float(np.mean(rates)) if rates else float("nan")


def timestamp_ba(truth: list[np.ndarray], predicted: list[np.ndarray]) -> float:
    """Timestamp-level balanced accuracy over every (log, frame): ``truth[i]`` / ``predicted[i]`` ``[F_i]`` bool."""
    return balanced_accuracy(np.concatenate(truth), np.concatenate(predicted))


def log_ba(truth: list[np.ndarray], predicted: list[np.ndarray]) -> float:
    """Log-level balanced accuracy: a log contains the scenario when any of its frames does."""
    return balanced_accuracy(np.array([t.any() for t in truth]), np.array([p.any() for p in predicted]))
