"""The search query set: descriptions in varied wording with their ground-truth specs (``truth.AgentSpec``).

Single agents, relations, two-agent "while" conjunctions and descriptions that hold nowhere in the synthetic
world (nothing reverses, no purple trucks, no highway, no cyclists): ``QueryCase.negative`` marks what the
set *intends* as a negative; the evaluation reports what the ground truth finds. World behaviour names
that equal a vocabulary class name ("parked", "stopped", "standing", "crossing") are written with the
vocabulary constant.
"""

from __future__ import annotations

from dataclasses import dataclass

from simsplat_core.eval.search.truth import AgentSpec
from simsplat_core.scenario import vocabulary as voc

CAR = ("sedan", "hatchback", "SUV")
EGO = ("ego",)
TRUCK = ("truck", "pickup truck")
PED = ("pedestrian",)
STILL_VEHICLE = (voc.PARKED, voc.STOPPED, "stop")


@dataclass(frozen=True)
class QueryCase:
    """One query: the text, its ground-truth agents (all must hold in a frame), whether it should hold nowhere."""

    text: str
    truth: tuple[AgentSpec, ...]
    negative: bool = False


def _v(**kw: object) -> AgentSpec:
    return AgentSpec(categories=("vehicle",), **kw)  # type: ignore[arg-type]


def _p(**kw: object) -> AgentSpec:
    return AgentSpec(categories=PED, **kw)  # type: ignore[arg-type]


QUERIES: tuple[QueryCase, ...] = (
    # single agents
    QueryCase("a vehicle turning right", (_v(behaviors=("turn_right",), phase="turn"),)),
    QueryCase("an SUV making a right turn", (_v(subtypes=("SUV",), behaviors=("turn_right",), phase="turn"),)),
    QueryCase("a car hanging a left", (_v(subtypes=CAR, behaviors=("turn_left",), phase="turn"),)),
    QueryCase("someone crossing the street", (_p(behaviors=(voc.CROSSING,), phase="cross"),)),
    QueryCase("a ped walking across the road", (_p(behaviors=(voc.CROSSING,), phase="cross"),)),
    QueryCase("a parked car", (_v(subtypes=CAR, behaviors=(voc.PARKED,)),)),
    QueryCase("vans parked by the curb", (_v(subtypes=("van",), behaviors=(voc.PARKED,)),)),
    QueryCase("a vehicle that is slowing down", (_v(behaviors=("slow_down", "stop"), phase="decelerate"),)),
    QueryCase("a car braking to a halt", (_v(subtypes=CAR, behaviors=("stop",), phase="decelerate"),)),
    QueryCase("a car switching to the left lane", (_v(subtypes=CAR, behaviors=("lane_change_left",),
                                                      phase="lane_change"),)),
    QueryCase("a vehicle merging right", (_v(behaviors=("lane_change_right",), phase="lane_change"),)),
    QueryCase("a person standing still", (_p(behaviors=(voc.STANDING,)),)),
    QueryCase("a pedestrian strolling along the sidewalk", (_p(behaviors=("walking",)),)),
    QueryCase("a car waiting in its lane", (_v(subtypes=CAR, behaviors=(voc.STOPPED,)),)),
    QueryCase("a bus driving straight", (_v(subtypes=("bus",), behaviors=("straight",), phase="move"),)),
    QueryCase("a pedestrian on the crosswalk", (_p(place="crosswalk"),)),
    QueryCase("a vehicle at the intersection", (_v(place="junction"),)),
    QueryCase("a red car", (_v(subtypes=CAR, colors=("red",)),)),
    # relations
    QueryCase("a pedestrian crossing in front of us", (_p(behaviors=(voc.CROSSING,), phase="cross", sector="front"),)),
    QueryCase("a car behind our car", (_v(subtypes=CAR, sector="behind"),)),
    QueryCase("a car following another car", (_v(subtypes=CAR, phase="move", following=_v(subtypes=CAR)),)),
    QueryCase("a vehicle following the bus", (_v(phase="move", following=_v(subtypes=("bus",))),)),
    # the synthetic ego never drives up to a standing vehicle in its route: a negative (a straight box ahead of a
    # turning ego swept over oncoming parked cars for 2 frames in 2 logs before the ego lane followed the route)
    QueryCase("a stopped vehicle blocking our lane", (_v(behaviors=STILL_VEHICLE, phase="still", in_ego_lane=True),),
              negative=True),
    QueryCase("the ego lane blocked by a parked truck", (_v(subtypes=TRUCK,
                                                            behaviors=STILL_VEHICLE, phase="still",
                                                            in_ego_lane=True),)),
    QueryCase("a vehicle stopped on the crosswalk", (_v(phase="still", place="crosswalk"),)),
    # two agents at once
    QueryCase("a pedestrian crossing in front of ego while a car turns right",
              (_p(behaviors=(voc.CROSSING,), phase="cross", sector="front"),
               _v(subtypes=CAR, behaviors=("turn_right",), phase="turn"))),
    QueryCase("someone crossing the road as a vehicle slows down",
              (_p(behaviors=(voc.CROSSING,), phase="cross"), _v(behaviors=("slow_down", "stop"), phase="decelerate"))),
    QueryCase("a parked van and a person standing on the sidewalk",
              (_v(subtypes=("van",), behaviors=(voc.PARKED,)), _p(behaviors=(voc.STANDING,), place="sidewalk"))),
    QueryCase("a car turning left while a pedestrian crosses the street",
              (_v(subtypes=CAR, behaviors=("turn_left",), phase="turn"), _p(behaviors=(voc.CROSSING,), phase="cross"))),
    # negatives: hold nowhere in the synthetic world
    QueryCase("a reversing bus", (_v(subtypes=("bus",), behaviors=("reverse",)),), negative=True),
    QueryCase("a purple truck", (_v(subtypes=("truck",), colors=("purple",)),), negative=True),
    QueryCase("a pedestrian on the highway shoulder", (_p(place="highway"),), negative=True),
    QueryCase("a car backing out", (_v(subtypes=CAR, behaviors=("reverse",)),), negative=True),
    QueryCase("a cyclist crossing the intersection", (AgentSpec(categories=("cyclist",)),), negative=True),
    QueryCase("a motorbike changing lanes", (_v(subtypes=("motorcycle",)),), negative=True),
    QueryCase("a pink bus turning left", (_v(subtypes=("bus",), colors=("pink",)),), negative=True),
    QueryCase("a bus reversing while someone stands on the sidewalk",
              (_v(subtypes=("bus",), behaviors=("reverse",)), _p(behaviors=(voc.STANDING,))), negative=True),
    QueryCase("a truck in a roundabout", (_v(subtypes=("truck",), place="roundabout"),), negative=True),
)

#: The ego as a subject and relations to the ego (the synthetic ego drives its route at a constant speed).
EGO_QUERIES: tuple[QueryCase, ...] = (
    QueryCase("while we turn left", (AgentSpec(categories=EGO, behaviors=("turn_left",), phase="turn"),)),
    QueryCase("a car turning right while we turn left",
              (_v(subtypes=CAR, behaviors=("turn_right",), phase="turn"),
               AgentSpec(categories=EGO, behaviors=("turn_left",), phase="turn"))),
    QueryCase("pedestrians crossing in front of us as our car turns right",
              (_p(behaviors=(voc.CROSSING,), phase="cross", sector="front"),
               AgentSpec(categories=EGO, behaviors=("turn_right",), phase="turn"))),
    QueryCase("a car following us", (_v(subtypes=CAR, phase="move", following=AgentSpec(categories=EGO)),)),
    QueryCase("a vehicle cutting in front of us", (_v(behaviors=("lane_change_left", "lane_change_right"),
                                                      phase="lane_change", cut_in=True),)),
    QueryCase("a pedestrian crossing in front of the ego",
              (_p(behaviors=(voc.CROSSING,), phase="cross", sector="front"),)),
    QueryCase("as our car slows down", (AgentSpec(categories=EGO, behaviors=("slow_down", "stop"),
                                                  phase="decelerate"),), negative=True),
    QueryCase("when the ego is stopped at the intersection",
              (AgentSpec(categories=EGO, phase="still", place="junction"),), negative=True),
)

#: Wording users type: terse lower case, questions, requests, plurals and counts, synonyms.
WORDING_QUERIES: tuple[QueryCase, ...] = (
    QueryCase("ped crossing ahead", (_p(behaviors=(voc.CROSSING,), phase="cross", sector="front"),)),
    QueryCase("suv turning right", (_v(subtypes=("SUV",), behaviors=("turn_right",), phase="turn"),)),
    QueryCase("person walking on the sidewalk", (_p(behaviors=("walking",)),)),
    QueryCase("vehicle slowing down while a ped crosses",
              (_v(behaviors=("slow_down", "stop"), phase="decelerate"), _p(behaviors=(voc.CROSSING,), phase="cross"))),
    QueryCase("Where does a pickup turn right?", (_v(subtypes=("pickup truck",), behaviors=("turn_right",),
                                                     phase="turn"),)),
    QueryCase("where does a truck turn left?", (_v(subtypes=TRUCK, behaviors=("turn_left",), phase="turn"),),
              negative=True),
    QueryCase("any cars reversing", (_v(subtypes=CAR, behaviors=("reverse",)),), negative=True),
    QueryCase("show me cars stopped at the intersection",
              (_v(subtypes=CAR, behaviors=STILL_VEHICLE, phase="still", place="junction"),)),
    QueryCase("are there any vans parked?", (_v(subtypes=("van",), behaviors=(voc.PARKED,)),)),
    QueryCase("a lorry braking to a stop", (_v(subtypes=TRUCK, behaviors=("stop",), phase="decelerate"),)),
    QueryCase("a silver car", (_v(subtypes=CAR, colors=("silver",)),)),
    QueryCase("black SUV", (_v(subtypes=("SUV",), colors=("black",)),)),
    QueryCase("two pedestrians walking together", (_p(behaviors=("walking",), count=2, together=True),)),
    QueryCase("a pair of cars turning right", (_v(subtypes=CAR, behaviors=("turn_right",), phase="turn", count=2),)),
    QueryCase("cyclist", (AgentSpec(categories=("cyclist",)),), negative=True),
    QueryCase("a bus on the motorway", (_v(subtypes=("bus",), place="motorway"),), negative=True),
)

#: Every query of the evaluation.
ALL_QUERIES: tuple[QueryCase, ...] = QUERIES + EGO_QUERIES + WORDING_QUERIES
