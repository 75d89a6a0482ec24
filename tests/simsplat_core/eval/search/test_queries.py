"""The search query set: well-formed specs that can only be true in the synthetic world where they mean to be."""

from __future__ import annotations

import pytest

from simsplat_core.eval.search.queries import ALL_QUERIES, EGO_QUERIES, QUERIES, WORDING_QUERIES, QueryCase
from simsplat_core.eval.search.truth import PHASES, AgentSpec
from simsplat_core.world.palette import VEHICLE_KIND_BY_NAME, WORLD_COLOR_NAMES

#: The behaviour labels the synthetic world scripts (``world.behaviors``: ``Motion.behavior``).
WORLD_BEHAVIORS = frozenset({"straight", "turn_left", "turn_right", "stop", "stopped", "slow_down",
                             "lane_change_left", "lane_change_right", "parked", "crossing", "walking", "standing"})
CATEGORIES = frozenset({"vehicle", "pedestrian", "cyclist", "ego"})
PLACES = frozenset({"", "crosswalk", "junction", "road", "sidewalk"})
SECTORS = frozenset({"", "front", "behind", "left", "right"})


def _specs(case: QueryCase) -> list[AgentSpec]:
    out = []
    for first in case.truth:
        spec: AgentSpec | None = first
        while spec is not None:
            out.append(spec)
            spec = spec.following
    return out


def test_the_full_set_is_the_three_sets_without_repeats() -> None:
    assert ALL_QUERIES == QUERIES + EGO_QUERIES + WORDING_QUERIES
    texts = [c.text for c in ALL_QUERIES]
    assert len(set(texts)) == len(texts)
    assert all(c.truth for c in ALL_QUERIES)


@pytest.mark.parametrize("case", ALL_QUERIES, ids=lambda c: c.text)
def test_every_spec_uses_known_phases_categories_and_sectors(case: QueryCase) -> None:
    for spec in _specs(case):
        assert spec.phase in PHASES
        assert set(spec.categories) <= CATEGORIES
        assert spec.sector in SECTORS
        assert spec.count >= 1


@pytest.mark.parametrize("case", [c for c in ALL_QUERIES if not c.negative], ids=lambda c: c.text)
def test_positive_queries_name_only_what_the_world_has(case: QueryCase) -> None:
    """A misspelt behaviour, subtype, colour or place would silently turn a positive query into a negative one."""
    for spec in _specs(case):
        assert set(spec.behaviors) <= WORLD_BEHAVIORS, spec.behaviors
        assert set(spec.subtypes) <= set(VEHICLE_KIND_BY_NAME), spec.subtypes
        assert set(spec.colors) <= set(WORLD_COLOR_NAMES), spec.colors
        assert spec.place in PLACES and "cyclist" not in spec.categories


def test_negatives_are_in_every_set_and_each_names_something_the_world_lacks() -> None:
    for group in (QUERIES, EGO_QUERIES, WORDING_QUERIES):
        assert any(c.negative for c in group) and any(not c.negative for c in group)
    for case in (c for c in QUERIES if c.negative and c.text != "a stopped vehicle blocking our lane"):
        lacks = [s for s in _specs(case) if not set(s.behaviors) <= WORLD_BEHAVIORS
                 or not set(s.subtypes) <= set(VEHICLE_KIND_BY_NAME) or not set(s.colors) <= set(WORLD_COLOR_NAMES)
                 or s.place not in PLACES or "cyclist" in s.categories]
        assert lacks, case.text
