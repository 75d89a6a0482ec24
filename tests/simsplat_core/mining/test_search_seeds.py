"""Search hits seed the mining loop with variants of what each hit's subject does."""

from __future__ import annotations

import pytest

from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.mining.search_seeds import hit_variants
from simsplat_core.search.engine import SearchHit

KINDS = {"s1": {"ped_01": "pedestrian", "veh_02": "vehicle", "cone_0": "static"}, "s2": {"veh_07": "vehicle"}}


def test_each_subject_is_varied_once_per_log_with_its_kinds_variants() -> None:
    hits = [SearchHit("s1", ("ped_01", "veh_02"), (3, 9), 0.9), SearchHit("s1", ("ped_01",), (20, 30), 0.8),
            SearchHit("s2", ("ego", "veh_07"), (0, 5), 0.7), SearchHit("s1", ("cone_0",), (0, 39), 0.5),
            SearchHit("s2", ("ego",), (0, 5), 0.4)]
    seeds = hit_variants(hits, KINDS, per_hit=2)
    assert [p.target_id for p in seeds["s1"]] == ["ped_01", "ped_01", "cone_0"]  # the second ped_01 hit adds none
    assert [p.category for p in seeds["s1"]] == ["modify_pedestrian", "modify_pedestrian", "remove"]
    assert [p.target_id for p in seeds["s2"]] == ["veh_07", "veh_07"]  # the ego is never a subject
    for proposal in seeds["s1"] + seeds["s2"]:  # the words name the object, and the editor's parser reads them so
        (command,) = parse_prompt(proposal.prompt).commands
        assert command.target is not None and command.target.object_id == proposal.target_id
        assert command.op == ("remove" if proposal.category == "remove" else "modify")
    with pytest.raises(ValueError, match="per_hit"):
        hit_variants(hits, KINDS, per_hit=0)
