"""Track and map-feature ids: the source's integers kept, stable new ones otherwise."""

from __future__ import annotations

from simsplat_core.export.ids import feature_ids, track_ids


def test_integer_object_ids_and_the_sdc_id_survive() -> None:
    ids = track_ids(["812", "17", "3"], "ego", other_ids=["inserted_1"], sdc_source_id="99")
    assert ids.from_source and ids.of("812") == 812 and ids.of("17") == 17 and ids.of("ego") == 99
    assert ids.of("inserted_1") == 813


def test_other_ids_are_numbered_stably_whatever_was_inserted() -> None:
    plain = track_ids(["car_b", "car_a", "ped_1"], "ego")
    edited = track_ids(["car_b", "car_a", "ped_1"], "ego", other_ids=["ins_2", "ins_1"])
    assert not plain.from_source
    assert [plain.of(o) for o in ("car_a", "car_b", "ped_1")] == [1, 2, 3] and plain.of("ego") == 0
    assert all(edited.of(o) == plain.of(o) for o in ("car_a", "car_b", "ped_1", "ego"))
    assert (edited.of("ins_1"), edited.of("ins_2")) == (4, 5)


def test_a_clashing_sdc_id_gets_a_free_one() -> None:
    ids = track_ids(["0", "1"], "ego", sdc_source_id="1")
    assert ids.of("ego") == 2 and len(set(ids.ids.values())) == 3


def test_feature_ids_from_suffixes_or_numbered() -> None:
    assert feature_ids(["lane_12", "road_edge_3", "stop_sign_40"]) == {"lane_12": 12, "road_edge_3": 3,
                                                                       "stop_sign_40": 40}
    clash = feature_ids(["lane_1", "road_edge_1", "crosswalk"])
    assert sorted(clash.values()) == [1, 2, 3] and clash["crosswalk"] == 1
