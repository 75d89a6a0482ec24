"""Splitting free-form grounding queries into appearance, motion and location parts (no text encoder)."""

from __future__ import annotations

import pytest

from simsplat_core.language.grounding.parse import crossing_direction, find_spans, normalise, parse_query
from simsplat_core.scenario import vocabulary as voc


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            "the black car turning left at the intersection",
            dict(
                categories=("vehicle",),
                subtype="car",
                colors=("black",),
                motion="turning left",
                sector="",
                context="at the intersection",
                group=False,
            ),
        ),
        (
            "find me the pedestrian in a red shirt and blue pants crossing from left to right",
            dict(
                categories=("pedestrian",),
                upper_color="red",
                lower_color="blue",
                colors=(),
                motion="crossing from left to right",
                crossing_direction="left_to_right",
                group=False,
            ),
        ),
        (
            "which SUV is parked on the right?",
            dict(
                categories=("vehicle",),
                subtype="SUV",
                noun="SUV",
                motion=voc.PARKED,
                sector="on the right",
                context="",
                appearance="SUV",
                group=False,
            ),
        ),
        (
            "all crossing pedestrians",
            dict(categories=("pedestrian",), motion=voc.CROSSING, group=True, noun="pedestrian"),
        ),
        ("every parked car", dict(categories=("vehicle",), motion=voc.PARKED, group=True)),
        ("the saloon cars", dict(subtype="sedan", group=True)),  # a plural compound noun is a group
        ("the saloon car", dict(subtype="sedan", group=False)),
        ("the purple bus", dict(subtype="bus", colors=("purple",), motion="", sector="", context="", group=False)),
        (
            "Show me the white sedan that is making a right turn.",
            dict(subtype="sedan", colors=("white",), motion="making a right turn"),
        ),
        ("the car ahead of us that is slowing down", dict(motion="slowing down", sector="ahead of us")),
        ("the grey van behind us", dict(subtype="van", colors=("gray",), sector="behind us")),
        (
            "the red hatchback in the oncoming lane",
            dict(subtype="hatchback", colors=("red",), context="in the oncoming lane"),
        ),
        (
            "the orange traffic cone by the curb",
            dict(categories=("static",), subtype="traffic cone", colors=("orange",), context="by the curb"),
        ),
        ("the stop sign", dict(categories=("sign",), subtype="stop sign")),
        ("the bicycle", dict(categories=("cyclist",), subtype="bicycle")),
        (
            "a person in a blue jacket walking along the sidewalk",
            dict(upper_color="blue", lower_color=None, motion="walking along the sidewalk", context=""),
        ),
        ("pedestrians standing on the sidewalk", dict(motion=voc.STANDING, context="on the sidewalk", group=True)),
        ("the person on the pedestrian crossing", dict(motion="", context="on the pedestrian crossing")),
        ("the person crossing at the crosswalk", dict(motion=voc.CROSSING, context="at the crosswalk")),
        (
            "the van going straight through the intersection",
            dict(motion="going straight", context="through the intersection"),
        ),
        ("the car right ahead of us", dict(motion="", sector="right ahead of us")),
        ("the car turning to the left of the ego car", dict(motion="turning", sector="to the left of the ego car")),
        ("the vehicle on my left turning a corner", dict(motion="turning a corner", sector="on my left")),
        ("the left-turning SUV", dict(subtype="SUV", motion="left-turning")),
        (
            "I'm looking for a vehicle that is continuing straight, on my left.",
            dict(motion="continuing straight", sector="on my left"),
        ),
        ("the car changing lanes to the left", dict(motion="changing lanes to the left", sector="")),
        ("the blue car merging into the left lane", dict(motion="merging into the left lane", sector="")),
        ("the truck backing up", dict(subtype="truck", motion="backing up")),
        (
            "the kid in a yellow top and brown trousers standing on the left of ego",
            dict(
                subtype="child",
                upper_color="yellow",
                lower_color="brown",
                motion=voc.STANDING,
                sector="on the left of ego",
            ),
        ),
        ("both cars parked by the curb", dict(group=True, motion=voc.PARKED, context="by the curb")),
        ("the vehicles in the lane coming towards us", dict(group=True, context="in the lane coming towards us")),
        (
            "that red ride hanging a left by the crossroads",
            dict(subtype="car", colors=("red",), motion="hanging a left", context="by the crossroads"),
        ),
        (
            "the woman dressed in red",
            dict(categories=("pedestrian",), colors=("red",), upper_color=None, lower_color=None),
        ),
        (
            "Select every one of the people wearing red jackets and black pants.",
            dict(group=True, categories=("pedestrian",), upper_color="red", lower_color="black"),
        ),
    ],
)
def test_parse_phrasings(text: str, expected: dict) -> None:
    parsed = parse_query(text)
    for field, value in expected.items():
        assert getattr(parsed, field) == value, (field, parsed)


@pytest.mark.parametrize(
    ("text", "direction"),
    [
        ("the pedestrian crossing from left to right", "left_to_right"),
        ("the pedestrian crossing from right to left", "right_to_left"),
        ("the guy crossing the street right to left", "right_to_left"),
        ("someone crossing over left-to-right", "left_to_right"),
        ("a person walking across the road from the left to the right", "left_to_right"),
        ("someone walking over to the right side", "left_to_right"),
        ("the walker heading across the road towards the left", "right_to_left"),
        ("the pedestrian walking from left to right", "left_to_right"),
        ("the pedestrian crossing the street", None),
        ("the car turning left", None),
    ],
)
def test_crossing_direction_is_explicit(text: str, direction: str | None) -> None:
    parsed = parse_query(text)
    assert parsed.crossing_direction == direction
    if direction is not None:
        assert "cross" in parsed.motion or parsed.motion.startswith(("walking", "heading"))


def test_crossing_direction_of_phrases() -> None:
    assert crossing_direction("from the right to the left") == "right_to_left"
    assert crossing_direction("over to the right side") == "left_to_right"
    assert crossing_direction("crossing the street") is None


def test_garment_order_is_kept() -> None:
    a = parse_query("the person in a red shirt and blue pants")
    b = parse_query("the person in a blue shirt and red pants")
    assert (a.upper_color, a.lower_color) == ("red", "blue")
    assert (b.upper_color, b.lower_color) == ("blue", "red")
    c = parse_query("the man wearing blue jeans and a white t-shirt")
    assert (c.upper_color, c.lower_color) == ("white", "blue")


def test_colour_synonyms_map_to_captioner_names() -> None:
    assert parse_query("the navy SUV").colors == ("blue",)
    assert parse_query("the grey sedan").colors == ("gray",)
    assert parse_query("the maroon pickup truck").colors == ("red",)


def test_vehicle_colours_are_not_garments() -> None:
    parsed = parse_query("the red car with a white top")
    assert parsed.upper_color is None and set(parsed.colors) == {"red", "white"}


def test_turn_direction_is_motion_and_side_is_location() -> None:
    parsed = parse_query("the car on the right turning left")
    assert parsed.motion == "turning left"
    assert parsed.sector == "on the right"


def test_moving_to_the_left_of_something_is_a_place_not_a_direction() -> None:
    parsed = parse_query("the grey vehicle not moving to the left of the ego car")
    assert parsed.motion == "not moving" and parsed.crossing_direction is None
    assert parsed.sector.startswith("to the left")
    assert parse_query("the man walking to the left").crossing_direction == "right_to_left"


def test_group_words_and_plurals() -> None:
    assert parse_query("all the white vans").group
    assert parse_query("each pedestrian standing still").group
    assert parse_query("the two cars waiting at the light").group
    assert parse_query("Which cars are parked?").group
    assert not parse_query("the car that is parked").group
    assert not parse_query("someone crossing").group


def test_regular_plurals_of_irregular_nouns_are_groups() -> None:
    """Users write "lorrys" for "lorries": the regular plural of a noun still asks for every match."""
    lorries = parse_query("Remove the red lorrys")
    assert lorries.group and lorries.noun == "lorry"
    assert parse_query("the childs crossing the road").group
    assert not parse_query("the red lorry").group


def test_appearance_text_and_extra_words() -> None:
    parsed = parse_query("Could you please show me the red SUV turning left?")
    assert parsed.appearance == "red SUV"
    assert parsed.appearance_extra == "red"
    assert parse_query("every parked car").appearance_extra == ""
    assert parse_query("the pedestrian in a red shirt").appearance_extra == "red shirt"


def test_motion_text_carries_the_subject_noun() -> None:
    assert parse_query("the white vans that are parked").motion_text == "van parked"
    assert parse_query("something reversing").motion_text == voc.REVERSING
    assert parse_query("the white van").motion_text == ""


def test_subject_for_messages() -> None:
    assert parse_query("all crossing pedestrians").subject() == "pedestrian"
    assert parse_query("the purple bus").subject() == "purple bus"
    assert parse_query("the person in a red shirt and blue pants").subject() == "person in a red top and blue trousers"


def test_spans_do_not_overlap_and_are_ordered() -> None:
    text = normalise("The black car, turning left at the intersection -- on my right!")
    spans = find_spans(text)
    assert [s.kind for s in spans] == ["motion", "context", "sector"]
    for a, b in zip(spans, spans[1:]):
        assert a.end <= b.start
    assert all(text[s.start : s.end] == s.text for s in spans)


def test_normalise() -> None:
    assert normalise("  Where's the  SUV?! ") == "where's the suv"
    assert normalise("the left-hand side") == "the left-hand side"


@pytest.mark.parametrize("text", ["", "   "])
def test_empty_query_is_rejected(text: str) -> None:
    with pytest.raises(ValueError, match="empty"):
        parse_query(text)


@pytest.mark.parametrize(
    ("text", "excluded", "colors", "appearance"),
    [
        ("the car that is not red", ("red",), (), "car"),
        ("a non-white van", ("white",), (), "van"),
        ("any SUV other than the black one", ("black",), (), "SUV"),
        ("the car that isn't grey turning left", ("gray",), (), "car"),
        ("the car that is neither red nor white", ("red", "white"), (), "car"),
        ("the red car", (), ("red",), "red car"),
    ],
)
def test_negated_colours_are_excluded_and_leave_the_text(text, excluded, colors, appearance):
    q = parse_query(text)
    assert q.excluded_colors == excluded
    assert q.colors == colors
    assert q.appearance == appearance
    assert "not" not in q.appearance.split()


def test_negated_colours_name_the_subject():
    assert parse_query("the sedan that is not red or white").excluded_colors == ("red", "white")
    assert parse_query("the sedan that is not red").subject() == "sedan that is not red"


@pytest.mark.parametrize(
    ("text", "motion", "sector"),
    [
        ("where's that grey SUV not moving right there?", "not moving", ""),
        ("the SUV switching to the lane on its right right there", "switching to the lane on its right", ""),
        ("the walker on the right strolling along the sidewalk over here", "strolling along the sidewalk",
         "on the right"),
        ("the car moving right", "moving right", ""),
    ],
)
def test_pointing_phrases_are_not_directions(text, motion, sector):
    q = parse_query(text)
    assert (q.motion, q.sector) == (motion, sector)
