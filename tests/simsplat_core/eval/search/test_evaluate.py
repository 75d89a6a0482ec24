"""Scoring the search per query: results paired with logs by position, summaries over positives and negatives."""

from __future__ import annotations

import dataclasses
import logging

import pytest

from simsplat_core.eval.search.evaluate import evaluate_queries, summarise
from simsplat_core.eval.search.queries import QueryCase
from simsplat_core.eval.search.truth import AgentSpec
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.search.frames import log_frames
from simsplat_core.search.logs import SearchableLog
from simsplat_core.types import SceneLog

CROSSING = QueryCase("someone crossing the street",
                     (AgentSpec(categories=("pedestrian",), behaviors=(voc.CROSSING,), phase="cross"),))


def _item(log: SceneLog) -> SearchableLog:
    return SearchableLog(log, None, log_frames(log))


def _without_pedestrians(log: SceneLog) -> SceneLog:
    """The same log (same seq_id: a second store's copy) with every pedestrian removed."""
    keep = {o.object_id for o in log.objects if o.category != "pedestrian"}
    return dataclasses.replace(log, tracks=tuple(t for t in log.tracks if t.object_id in keep),
                               objects=tuple(o for o in log.objects if o.object_id in keep))


@pytest.fixture(scope="module")
def two_copies(synthetic_log: SceneLog) -> tuple[SearchableLog, SearchableLog]:
    return _item(synthetic_log), _item(_without_pedestrians(synthetic_log))


def test_logs_sharing_a_seq_id_are_scored_against_their_own_results(
        two_copies: tuple[SearchableLog, SearchableLog]) -> None:
    with_peds, without = two_copies
    assert with_peds.log.seq_id == without.log.seq_id
    for items in ([with_peds, without], [without, with_peds]):
        (row,) = evaluate_queries(list(items), (CROSSING,))
        assert row["logs_true"] == 1 and row["logs_hit"] == 1  # only the log with pedestrians holds and is hit
        assert row["log_ba"] == pytest.approx(1.0)  # paired by seq_id, both logs would get one log's results
        assert not row["negative"] and row["hits"] >= 1


def test_a_negative_row_and_a_warning_when_a_meant_negative_holds(
        two_copies: tuple[SearchableLog, SearchableLog], caplog: pytest.LogCaptureFixture) -> None:
    _, without = two_copies
    (row,) = evaluate_queries([without], (CROSSING,))
    assert row["negative"] and row["logs_true"] == 0 and row["logs_hit"] == 0 and row["hits"] == 0
    assert row["log_ba"] == pytest.approx(1.0)  # the only rate there is: the true-negative one
    meant_negative = dataclasses.replace(CROSSING, negative=True)
    with caplog.at_level(logging.WARNING, logger="simsplat_core.eval.search.evaluate"):
        (row,) = evaluate_queries([two_copies[0]], (meant_negative,))
    assert not row["negative"] and "meant as a negative holds in 1 logs" in caplog.text


def _row(negative: bool, ts: float | None, log: float | None, hits: int, seconds: float = 0.1) -> dict:
    return {"query": "q", "negative": negative, "timestamp_ba": ts, "log_ba": log, "hits": hits, "logs_true": 0,
            "logs_hit": 0, "seconds": seconds}


def test_summary_means_over_all_positives_and_negatives() -> None:
    rows = [_row(False, 0.8, 1.0, 3, 0.2), _row(False, 0.6, None, 1, 0.4), _row(True, 1.0, 1.0, 0, 0.0),
            _row(True, 0.5, 0.5, 2, 0.2)]
    summary = summarise(rows)
    assert summary["queries"] == 4 and summary["negatives"] == 2
    assert summary["timestamp_ba"] == pytest.approx((0.8 + 0.6 + 1.0 + 0.5) / 4)
    assert summary["log_ba"] == pytest.approx((1.0 + 1.0 + 0.5) / 3, abs=1e-4)  # missing values left out (4 places)
    assert summary["timestamp_ba_positives"] == pytest.approx(0.7)
    assert summary["log_ba_positives"] == pytest.approx(1.0)
    assert summary["negatives_without_hits"] == 1
    assert summary["seconds_mean"] == pytest.approx(0.2)


def test_summary_of_positives_only_has_no_negative_counts() -> None:
    summary = summarise([_row(False, None, None, 0)])
    assert summary["negatives"] == 0 and summary["negatives_without_hits"] == 0
    assert summary["timestamp_ba"] != summary["timestamp_ba"]  # nan: nothing to average
