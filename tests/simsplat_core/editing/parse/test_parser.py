"""The edit prompt parser: a table of phrasings checked field by field, multi-edit prompts, pronouns,
refusals (reason and message), E5 for unknown verbs, and what it costs."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from simsplat_core.editing.commands import program_from_json, program_to_json
from simsplat_core.editing.parse.anchor import motion_kinds
from simsplat_core.editing.parse.lexicon import SUPPORTED
from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.text import TextEncoder, default_text_encoder

from .parser_checks import program_mismatches


@pytest.fixture(scope="session")
def encoder() -> TextEncoder:
    return default_text_encoder()


REM, INS, REP, MOD = "remove", "insert", "replace", "modify"
TD, TG = "target.description~", "target.group"
AC, AK, AS, AN = "asset.category", "asset.color", "asset.subtype", "asset.count"
PR, PA, PD, PL = "placement.relation", "placement.anchor.description~", "placement.distance_m", "placement.lane"
SP_MODE, SP_VAL, SP_UNIT = "behaviour.speed.mode", "behaviour.speed.value", "behaviour.speed.unit"

REMOVE: list[tuple[str, list[dict[str, Any]]]] = [
    ("remove the white van", [{"op": REM, "target.description": "the white van", TG: False}]),
    ("Delete the bus.", [{"op": REM, "target.description": "the bus"}]),
    ("erase the pedestrian in the red shirt", [{"op": REM, "target.description": "the pedestrian in the red shirt"}]),
    ("get rid of the silver sedan on the left", [{"op": REM, "target.description": "the silver sedan on the left"}]),
    ("take out the truck", [{"op": REM, "target.description": "the truck"}]),
    ("take the truck out", [{"op": REM, "target.description": "the truck"}]),
    ("drop the parked car", [{"op": REM, "target.description": "the parked car"}]),
    ("remove all parked cars", [{"op": REM, "target.description": "all parked cars", TG: True}]),
    ("delete every cone", [{"op": REM, TD: "cone", TG: True}]),
    ("remove all crossing pedestrians", [{"op": REM, TD: "crossing pedestrians", TG: True}]),
    ("remove the pedestrians", [{"op": REM, TD: "pedestrians", TG: True}]),
    ("remove node 12", [{"op": REM, "target.node_id": 12, "target.description": None}]),
    ("delete object veh_03", [{"op": REM, "target.object_id": "veh_03"}]),
    ("remove node #7 please", [{"op": REM, "target.node_id": 7}]),
    ("remove the bus and the truck", [{"op": REM, TD: "bus"}, {"op": REM, TD: "truck"}]),
    ("get rid of the car between the bus and the truck",
     [{"op": REM, "target.description": "the car between the bus and the truck"}]),
    ("REMOVE THE RED CAR!!!", [{"op": REM, "target.description": "the red car"}]),
    ("pls delete the black SUV from the scene", [{"op": REM, "target.description": "the black suv"}]),
    ("can you erase the cyclist?", [{"op": REM, "target.description": "the cyclist"}]),
    ("clear away the barriers", [{"op": REM, TD: "barriers", TG: True}]),
    ("make the blue van disappear", [{"op": REM, "target.description": "the blue van"}]),
    ("the taxi should be removed", [{"op": REM, "target.description": "the taxi"}]),
    ("wipe out the construction worker", [{"op": REM, "target.description": "the construction worker"}]),
    ("remove the pedestrian crossing the street",
     [{"op": REM, "target.description": "the pedestrian crossing the street"}]),
    ("I'd like you to delete the van that's parked on the right",
     [{"op": REM, TD: "the van that is parked on the right"}]),
]

INSERT: list[tuple[str, list[dict[str, Any]]]] = [
    ("add a yellow taxi", [{"op": INS, AC: "vehicle", AK: "yellow", AS: "car", AN: 1, "placement": None}]),
    ("insert a pedestrian in a red coat on the crosswalk",
     [{"op": INS, AC: "pedestrian", AK: "red", "asset.description~": "red coat", PR: "on_crosswalk"}]),
    ("place a row of orange cones in the ego lane 20 m ahead",
     [{"op": INS, AC: "static", AS: "traffic cone", AK: "orange", "asset.count>": 1, PR: "in_lane", PL: "same",
       PD: 20.0, "placement.anchor": None}]),
    ("put three barriers in front of the truck",
     [{"op": INS, AS: "barrier", AN: 3, PR: "in_front_of", PA: "the truck"}]),
    ("add a car 2 m to the left of the white van",
     [{"op": INS, AC: "vehicle", PR: "left_of", PD: 2.0, "placement.anchor.description": "the white van"}]),
    ("spawn a cone in front of the construction worker",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the construction worker"}]),
    ("add a bus behind the bus ahead",
     [{"op": INS, AS: "bus", PR: "behind", "placement.anchor.description": "the bus ahead"}]),
    ("insert a car in the left lane 30 m ahead",
     [{"op": INS, PR: "in_lane", PL: "left", PD: 30.0, "placement.anchor": None}]),
    ("add a pedestrian on the sidewalk", [{"op": INS, AC: "pedestrian", PR: "on_sidewalk"}]),
    ("put a traffic cone next to the parked truck",
     [{"op": INS, AS: "traffic cone", PR: "next_to", "placement.anchor.description": "the parked truck"}]),
    ("add a barrier at (10, -3, 0)", [{"op": INS, PR: "absolute", "placement.position": (10.0, -3.0, 0.0)}]),
    ("add a cone at x=12 y=3", [{"op": INS, PR: "absolute", "placement.position": (12.0, 3.0, 0.0)}]),
    ("add a car at (5, 2, 0) at frame 10", [{"op": INS, PR: "absolute", "placement.frame": 10}]),
    ("drop in a red sedan 15 metres ahead",
     [{"op": INS, AS: "sedan", AK: "red", PR: "in_front_of", PD: 15.0, "placement.anchor": None}]),
    ("introduce a white SUV in the oncoming lane 40 m ahead",
     [{"op": INS, AS: "SUV", AK: "white", PR: "in_lane", PL: "opposite", PD: 40.0}]),
    ("add two pedestrians on the crosswalk", [{"op": INS, AC: "pedestrian", AN: 2, PR: "on_crosswalk"}]),
    ("add a black and white police car behind us",
     [{"op": INS, "asset.description~": "black and white police car", AK: "black", PR: "behind",
       "placement.anchor": None}]),
    ("add a cone and a barrier in front of the truck",
     [{"op": INS, AS: "traffic cone", PR: "in_front_of", PA: "truck"},
      {"op": INS, AS: "barrier", PR: "in_front_of", PA: "truck"}]),
    ("add a cone in front of the truck and a barrier behind it",
     [{"op": INS, AS: "traffic cone", PR: "in_front_of", PA: "truck"},
      {"op": INS, AS: "barrier", PR: "behind", "placement.anchor.description": "the truck"}]),
    ("add a pedestrian crossing the street in front of the bus",
     [{"op": INS, AC: "pedestrian", PR: "in_front_of", PA: "bus", "behaviour.cross_street": True}]),
    ("put a yellow excavator behind the stopped silver sedan",  # every procedural kind, by name or alias
     [{"op": INS, AC: "static", "asset.subtype": "excavator", PR: "behind", PA: "stopped silver sedan"}]),
    ("add a digger on the road ahead", [{"op": INS, AC: "static", "asset.subtype": "excavator"}]),
    ("add a pedestrian crossing at the crosswalk ahead",  # a person: a crosswalk is not at a crosswalk
     [{"op": INS, AC: "pedestrian", PR: "on_crosswalk", "behaviour.cross_street": True}]),
    ("put a cone on the pedestrian crossing at the intersection",  # here the crossing is the place
     [{"op": INS, AS: "traffic cone", PR: "on_crosswalk"}]),
    ("add a car in the right lane driving at 50 km/h",
     [{"op": INS, PR: "in_lane", PL: "right", SP_MODE: "absolute", SP_VAL: 50.0, SP_UNIT: "km/h"}]),
    ("place a child 3 meters to the right of the red car",
     [{"op": INS, AC: "pedestrian", AS: "child", PR: "right_of", PD: 3.0, PA: "red car"}]),
    ("add a few cones on the road", [{"op": INS, AN: 3, PR: "on_road"}]),
    ("put five cones in a row 2 m apart in front of us",
     [{"op": INS, AN: 5, "asset.spacing_m": 2.0, PR: "in_front_of", "placement.anchor": None}]),
    ("add a motorcycle next to the cyclist", [{"op": INS, AS: "motorcycle", PR: "next_to", PA: "cyclist"}]),
    ("I want a yellow taxi in our lane 25 m ahead", [{"op": INS, AK: "yellow", PR: "in_lane", PL: "same", PD: 25.0}]),
    # a trailing ", same lane" makes it a lane placement (centre to centre along the lane), not a gap ahead
    ("Spawn a black sedan 10 m in front of us, same lane",
     [{"op": INS, AK: "black", PR: "in_lane", PL: "same", PD: 10.0, "placement.anchor": None}]),
    ("add a car 10 m ahead of us, our lane", [{"op": INS, PR: "in_lane", PL: "same", PD: 10.0}]),
    ("there should be a barrel on the sidewalk", [{"op": INS, AC: "static", AS: "barrel", PR: "on_sidewalk"}]),
    ("add another car behind the truck", [{"op": INS, AN: 1, PR: "behind", PA: "truck"}]),
    ("add a pickup truck facing the other way in the oncoming lane",
     [{"op": INS, AS: "pickup truck", PR: "in_lane", PL: "opposite", "placement.heading_deg": 180.0}]),
    ("add a bus 10m ahead of the white van", [{"op": INS, PR: "in_front_of", PD: 10.0, PA: "white van"}]),
    ("add a pedestrian in a blue jacket walking on the sidewalk",
     [{"op": INS, AK: "blue", PR: "on_sidewalk", "behaviour.gait": "walk"}]),
    ("add a pedestrian who runs across the road",
     [{"op": INS, AC: "pedestrian", "behaviour.cross_street": True, "behaviour.gait": "run"}]),
    ("add a car and make it turn left at the next intersection",
     [{"op": INS, AC: "vehicle", "behaviour.turn": "left"}]),
    ("add a silver car behind us and have it follow the bus",
     [{"op": INS, AK: "silver", PR: "behind", "behaviour.follow.description": "the bus"}]),
    ("add 2 cones 5 m behind the bus", [{"op": INS, AN: 2, PR: "behind", PD: 5.0, PA: "bus"}]),
    ("add a van ten meters behind the red car", [{"op": INS, AS: "van", PR: "behind", PD: 10.0, PA: "red car"}]),
    ("Add a truck on the left of the bus", [{"op": INS, PR: "left_of", PA: "bus"}]),
    ("add a pedestrian on the zebra crossing in front of the bus", [{"op": INS, PR: "on_crosswalk", PA: "bus"}]),
    ("put a cone on the road 30 m ahead", [{"op": INS, PR: "on_road", PD: 30.0}]),
    ("add a construction worker next to the barrier",
     [{"op": INS, AC: "pedestrian", PR: "next_to", "placement.anchor.description": "the barrier"}]),
]

REPLACE: list[tuple[str, list[dict[str, Any]]]] = [
    ("replace the grey car with a yellow taxi",
     [{"op": REP, "target.description": "the grey car", AK: "yellow", AS: "car", AN: 1}]),
    ("swap the van for a pickup truck", [{"op": REP, "target.description": "the van", AS: "pickup truck"}]),
    ("turn the red SUV into a bus", [{"op": REP, "target.description": "the red suv", AS: "bus"}]),
    ("change the white car into a black SUV", [{"op": REP, TD: "white car", AK: "black", AS: "SUV"}]),
    ("replace node 5 with a red truck", [{"op": REP, "target.node_id": 5, AS: "truck", AK: "red"}]),
    ("swap out the bus for a white van", [{"op": REP, "target.description": "the bus", AS: "van"}]),
    ("put a bus instead of the van", [{"op": REP, "target.description": "the van", AS: "bus"}]),
    ("substitute a taxi for the sedan", [{"op": REP, "target.description": "the sedan", AS: "car"}]),
    ("the sedan should be a police car",
     [{"op": REP, "target.description": "the sedan", "asset.description~": "police"}]),
    ("replace the pedestrian in the red coat with a woman in a green dress",
     [{"op": REP, TD: "pedestrian in the red coat", AC: "pedestrian", AK: "green"}]),
    ("replace all parked cars with trucks", [{"op": REP, TG: True, AS: "truck", AN: 1}]),
    ("exchange the cyclist with a motorcycle", [{"op": REP, TD: "cyclist", AS: "motorcycle"}]),
]

SPEED: list[tuple[str, list[dict[str, Any]]]] = [
    ("make the red car go 40 km/h", [{"op": MOD, TD: "red car", SP_MODE: "absolute", SP_VAL: 40.0, SP_UNIT: "km/h"}]),
    ("the truck should drive at 15 m/s", [{"op": MOD, TD: "truck", SP_VAL: 15.0, SP_UNIT: "m/s"}]),
    ("make the white van drive at 20km/h", [{"op": MOD, SP_MODE: "absolute", SP_VAL: 20.0, SP_UNIT: "km/h"}]),
    ("have the blue car go twice as fast", [{"op": MOD, SP_MODE: "factor", SP_VAL: 2.0}]),
    ("make the bus drive at half the speed", [{"op": MOD, SP_MODE: "factor", SP_VAL: 0.5}]),
    ("make the taxi 10 km/h slower", [{"op": MOD, SP_MODE: "delta", SP_VAL: -10.0, SP_UNIT: "km/h"}]),
    ("make the sedan go 5 mph faster", [{"op": MOD, SP_MODE: "delta", SP_VAL: 5.0, SP_UNIT: "mph"}]),
    ("make the SUV 50% faster", [{"op": MOD, SP_MODE: "factor", SP_VAL: 1.5}]),
    ("speed up the truck by 20 kph", [{"op": MOD, TD: "truck", SP_MODE: "delta", SP_VAL: 20.0, SP_UNIT: "km/h"}]),
    ("slow down the bus to 20 km/h",
     [{"op": MOD, TD: "bus", SP_MODE: "absolute", SP_VAL: 20.0, "behaviour.longitudinal": None}]),
    ("make the car drive ten km/h", [{"op": MOD, SP_MODE: "absolute", SP_VAL: 10.0, SP_UNIT: "km/h"}]),
    ("make the car go thirty miles per hour", [{"op": MOD, SP_VAL: 30.0, SP_UNIT: "mph"}]),
    ("make the van go 5 m/s", [{"op": MOD, SP_VAL: 5.0, SP_UNIT: "m/s"}]),
    ("let the sedan drive 60kmh", [{"op": MOD, SP_VAL: 60.0, SP_UNIT: "km/h"}]),
    ("make the pedestrian walk at 1.5 m/s", [{"op": MOD, SP_VAL: 1.5, SP_UNIT: "m/s", "behaviour.gait": "walk"}]),
    ("make the pedestrian walk twice as fast", [{"op": MOD, SP_MODE: "factor", SP_VAL: 2.0}]),
    ("make the car go three times faster", [{"op": MOD, SP_MODE: "factor", SP_VAL: 3.0}]),
    ("make the bus go 20% slower", [{"op": MOD, SP_MODE: "factor", SP_VAL: 0.8}]),
    ("accelerate the sedan to 60 km/h", [{"op": MOD, TD: "sedan", SP_MODE: "absolute", SP_VAL: 60.0}]),
    ("make the car accelerate", [{"op": MOD, "behaviour.longitudinal": "accelerate", "behaviour.speed": None}]),
    ("make the car speed up", [{"op": MOD, "behaviour.longitudinal": "accelerate"}]),
    ("have the van go faster", [{"op": MOD, "behaviour.longitudinal": "accelerate"}]),
    ("the bus should slow down", [{"op": MOD, TD: "bus", "behaviour.longitudinal": "decelerate"}]),
    ("make the truck ease off", [{"op": MOD, "behaviour.longitudinal": "decelerate"}]),
    ("make the car decelerate", [{"op": MOD, "behaviour.longitudinal": "decelerate"}]),
    ("have the sedan brake hard", [{"op": MOD, "behaviour.longitudinal": "brake_hard"}]),
    ("make the sedan slam on the brakes", [{"op": MOD, "behaviour.longitudinal": "brake_hard"}]),
    ("make the taxi hurry", [{"op": MOD, "behaviour.longitudinal": "accelerate"}]),
    ("make the car go at 50", [{"op": MOD, SP_MODE: "absolute", SP_VAL: 50.0, SP_UNIT: "km/h"}]),
]

STOP: list[tuple[str, list[dict[str, Any]]]] = [
    ("make the red car stop", [{"op": MOD, "target.description": "the red car", "behaviour.stop": "set",
                                "behaviour.stop.at_time_s": None, "behaviour.stop.before": None}]),
    ("stop the van", [{"op": MOD, "target.description": "the van", "behaviour.stop": "set"}]),
    ("make the car stop at 2 s", [{"op": MOD, "behaviour.stop.at_time_s": 2.0}]),
    ("make the bus stop after 1.5 seconds", [{"op": MOD, "behaviour.stop.at_time_s": 1.5}]),
    # "be standing still / stationary / at a standstill by T" is a stop by that time (the time was dropped)
    ("The red saloon car should be standing still after 2.5 secs.",
     [{"op": MOD, TD: "red saloon car", "behaviour.stop.at_time_s": 2.5}]),
    ("the van should be stationary by 3 seconds", [{"op": MOD, "behaviour.stop.at_time_s": 3.0}]),
    ("the silver car should be at a standstill by 2 s", [{"op": MOD, "behaviour.stop.at_time_s": 2.0}]),
    ("the truck should stop before the crosswalk", [{"op": MOD, TD: "truck", "behaviour.stop.before": "crosswalk"}]),
    ("stop the van before the intersection",
     [{"op": MOD, "target.description": "the van", "behaviour.stop.before": "intersection"}]),
    ("make the car stop behind the bus", [{"op": MOD, "behaviour.stop.behind.description": "the bus"}]),
    ("make the taxi come to a halt", [{"op": MOD, "behaviour.stop": "set"}]),
    ("make the bus pull over", [{"op": MOD, "behaviour.stop": "set"}]),
    ("make the car stop 5 m before the crosswalk",
     [{"op": MOD, "behaviour.stop.before": "crosswalk", "behaviour.stop.gap_m": 5.0}]),
    ("have the SUV stop at the stop line", [{"op": MOD, "behaviour.stop.before": "stop_line"}]),
    ("make the car at the stop sign stop", [{"op": MOD, "target.description": "the car at the stop sign",
                                             "behaviour.stop": "set"}]),
    ("make the van halt at the junction", [{"op": MOD, "behaviour.stop.before": "intersection"}]),
    ("make the car brake to a stop", [{"op": MOD, "behaviour.stop": "set"}]),
    ("make the white car stop 3 m behind the truck",
     [{"op": MOD, "behaviour.stop.behind.description": "the truck", "behaviour.stop.gap_m": 3.0}]),
]

MOTION: list[tuple[str, list[dict[str, Any]]]] = [
    ("make the car reverse", [{"op": MOD, "behaviour.reverse": True}]),
    ("back the pickup up", [{"op": MOD, "target.description": "the pickup", "behaviour.reverse": True}]),
    ("make the truck drive backwards", [{"op": MOD, "behaviour.reverse": True}]),
    ("reverse the red car", [{"op": MOD, "target.description": "the red car", "behaviour.reverse": True}]),
    ("let the saloon car that is to our right reverse out of its spot",
     [{"op": MOD, "target.description": "the saloon car that is to our right", "behaviour.reverse": True}]),
    ("make the red car back out of its parking space",
     [{"op": MOD, "target.description": "the red car", "behaviour.reverse": True}]),
    # where the ego is describes the target of a target-first verb; it is no stop place or complement
    ("delay the bus in front of us by 2 seconds",
     [{"op": MOD, "target.description": "the bus in front of us", "behaviour.delay_s": 2.0}]),
    ("stop the bus in front of me", [{"op": MOD, "target.description": "the bus in front of me",
                                      "behaviour.stop.before": None}]),
    ("delay the individual in front of us in the crosswalk by 1.5 s",
     [{"op": MOD, "target.description": "the individual in front of us in the crosswalk", "behaviour.delay_s": 1.5}]),
    ("stop the car in front of us before the crosswalk",
     [{"op": MOD, "target.description": "the car in front of us", "behaviour.stop.before": "crosswalk"}]),
    ("delay the pedestrian with a red top in front of me crossing the street by 2 seconds",
     [{"op": MOD, "target.description": "the pedestrian with a red top in front of me crossing the street",
       "behaviour.delay_s": 2.0, "behaviour.cross_street": False}]),
    ("make the car change lanes to the left", [{"op": MOD, "behaviour.lane_change": "left"}]),
    ("have the truck merge into the left lane", [{"op": MOD, "behaviour.lane_change": "left"}]),
    ("make the taxi cut in to the right", [{"op": MOD, "behaviour.lane_change": "right"}]),
    ("the bus should switch to the right lane", [{"op": MOD, TD: "bus", "behaviour.lane_change": "right"}]),
    ("make the van move over to the left lane", [{"op": MOD, "behaviour.lane_change": "left"}]),
    ("make the SUV do a lane change to the right", [{"op": MOD, "behaviour.lane_change": "right"}]),
    ("make the car turn left at the next intersection", [{"op": MOD, "behaviour.turn": "left"}]),
    ("have the bus turn right", [{"op": MOD, "behaviour.turn": "right"}]),
    ("make the truck take a left", [{"op": MOD, "behaviour.turn": "left"}]),
    ("make the sedan go straight at the intersection", [{"op": MOD, "behaviour.turn": "straight"}]),
    ("the van should not turn", [{"op": MOD, "behaviour.turn": "straight"}]),
    ("The car that is turning to the left at the crossroads should continue straight instead of turning.",
     [{"op": MOD, "target.description": "the car that is turning to the left at the crossroads",
       "behaviour.turn": "straight"}]),
    ("the car turning left should go straight instead of turning left",
     [{"op": MOD, "target.description": "the car turning left", "behaviour.turn": "straight"}]),
    ("the red car should go straight rather than making a right turn",
     [{"op": MOD, "target.description": "the red car", "behaviour.turn": "straight"}]),
    ("make the bus wait 2 s before moving", [{"op": MOD, "behaviour.start_time_s": 2.0, "behaviour.stop": None}]),
    ("make the car start 3 seconds later", [{"op": MOD, "behaviour.delay_s": 3.0}]),
    ("delay the truck by 2 seconds", [{"op": MOD, "target.description": "the truck", "behaviour.delay_s": 2.0}]),
    ("make the van start moving at 4 s", [{"op": MOD, "behaviour.start_time_s": 4.0}]),
    ("have the taxi wait for two seconds", [{"op": MOD, "behaviour.start_time_s": 2.0}]),
    ("the pedestrian should start 1.5 s late", [{"op": MOD, "behaviour.delay_s": 1.5}]),
    ("make the sedan follow the bus", [{"op": MOD, TD: "sedan", "behaviour.follow.description": "the bus"}]),
    ("have the white car tailgate the truck", [{"op": MOD, "behaviour.follow.description": "the truck"}]),
    ("make the car follow the van ahead", [{"op": MOD, "behaviour.follow.description": "the van ahead"}]),
    ("make the bus follow us", [{"op": MOD, "behaviour.follow.description": "ego"}]),
    ("make the van overtake the bus",
     [{"op": MOD, "behaviour.lane_change": "left", "behaviour.longitudinal": "accelerate"}]),
    ("move the van 5 m behind the bus", [{"op": MOD, TD: "van", PR: "behind", PD: 5.0, PA: "bus", "behaviour": None}]),
    ("shift the car 1 m to the left", [{"op": MOD, "behaviour.lateral_offset_m": 1.0}]),
]

PEDESTRIAN: list[tuple[str, list[dict[str, Any]]]] = [
    ("make the pedestrian cross the street", [{"op": MOD, "behaviour.cross_street": True, "behaviour.jaywalk": False}]),
    ("have the man in the blue shirt jaywalk",
     [{"op": MOD, "target.description": "the man in the blue shirt", "behaviour.jaywalk": True,
       "behaviour.cross_street": True}]),
    ("make the woman cross the road away from the crosswalk", [{"op": MOD, "behaviour.jaywalk": True}]),
    ("make the child run", [{"op": MOD, "behaviour.gait": "run"}]),
    ("make the pedestrian sprint", [{"op": MOD, "behaviour.gait": "run"}]),
    ("let the jogger jog", [{"op": MOD, "behaviour.gait": "run"}]),
    ("make all pedestrians walk", [{"op": MOD, TG: True, "behaviour.gait": "walk"}]),
    ("make the person run across the road", [{"op": MOD, "behaviour.cross_street": True, "behaviour.gait": "run"}]),
    ("make the pedestrian on the sidewalk cross at the crosswalk",
     [{"op": MOD, TD: "pedestrian on the sidewalk", "behaviour.cross_street": True, "behaviour.jaywalk": False}]),
    ("make the pedestrian walk slower",
     [{"op": MOD, "behaviour.longitudinal": "decelerate", "behaviour.gait": "walk"}]),
    ("make the kid hurry", [{"op": MOD, "behaviour.gait": "run"}]),
    ("make the pedestrian crossing the street run",
     [{"op": MOD, "target.description": "the pedestrian crossing the street", "behaviour.gait": "run"}]),
]

MULTI: list[tuple[str, list[dict[str, Any]]]] = [
    ("remove the white van and make the red car stop",
     [{"op": REM, "target.description": "the white van"},
      {"op": MOD, "target.description": "the red car", "behaviour.stop": "set"}]),
    ("delete the bus, then add a cone in front of the truck",
     [{"op": REM, TD: "bus"}, {"op": INS, AS: "traffic cone", PR: "in_front_of", PA: "truck"}]),
    ("make the car slow down and then stop at the crosswalk",
     [{"op": MOD, "behaviour.longitudinal": "decelerate", "behaviour.stop.before": "crosswalk"}]),
    ("make the bus stop and the car follow it",
     [{"op": MOD, TD: "bus", "behaviour.stop": "set"},
      {"op": MOD, TD: "car", "behaviour.follow.description": "the bus"}]),
    ("make the truck turn left; remove the cyclist",
     [{"op": MOD, "behaviour.turn": "left"}, {"op": REM, TD: "cyclist"}]),
    ("make the red car stop. Also remove the bus.", [{"op": MOD, "behaviour.stop": "set"}, {"op": REM, TD: "bus"}]),
    ("make the taxi change lanes to the left and then speed up",
     [{"op": MOD, "behaviour.lane_change": "left", "behaviour.longitudinal": "accelerate"}]),
    ("stop the car and remove the truck", [{"op": MOD, TD: "car"}, {"op": REM, TD: "truck"}]),
    ("make the car and the bus stop", [{"op": MOD, TD: "car"}, {"op": MOD, TD: "bus"}]),
    ("the car and the bus should stop", [{"op": MOD, TD: "car"}, {"op": MOD, TD: "bus"}]),
    ("remove the van, add a barrier next to the bus and make the taxi reverse",
     [{"op": REM}, {"op": INS, PR: "next_to"}, {"op": MOD, "behaviour.reverse": True}]),
    ("make the pedestrian cross the street and then run", [{"op": MOD, "behaviour.cross_street": True,
                                                             "behaviour.gait": "run"}]),
    ("make the sedan follow the bus and stop behind it",
     [{"op": MOD, "behaviour.follow.description": "the bus", "behaviour.stop.behind.description": "the bus"}]),
    ("add a pedestrian on the crosswalk and make them run", [{"op": INS, PR: "on_crosswalk", "behaviour.gait": "run"}]),
    ("remove the truck. make the white car go 30 km/h, then make it turn right",
     [{"op": REM}, {"op": MOD, SP_VAL: 30.0, "behaviour.turn": "right"}]),
]

#: Wordings met while trying the parser by hand (each once failed).
TYPED: list[tuple[str, list[dict[str, Any]]]] = [
    ("add a parked car on the right side of the road", [{"op": INS, PR: "on_road", "placement.anchor": None}]),
    ("Make the white SUV drive 10 km/h faster than now", [{"op": MOD, SP_MODE: "delta", SP_VAL: 10.0}]),
    ("Get the pedestrian to walk across the street",
     [{"op": MOD, "target.description": "the pedestrian", "behaviour.cross_street": True}]),
    ("Make the pedestrian wait 3 seconds before crossing",
     [{"op": MOD, "behaviour.start_time_s": 3.0, "behaviour.cross_street": True}]),
    ("add a cyclist riding on the right", [{"op": INS, AS: "bicycle", PR: "right_of", "behaviour": None}]),
    ("I'd like to see a red bus in front of the white van",
     [{"op": INS, AS: "bus", PR: "in_front_of", PA: "white van"}]),
    ("add a woman with a stroller on the sidewalk",
     [{"op": INS, "asset.description": "a woman with a stroller", PR: "on_sidewalk", "behaviour": None}]),
    ("add an SUV next to node 12", [{"op": INS, PR: "next_to", "placement.anchor.node_id": 12}]),
    ("remvoe the red car", [{"op": REM, "target.description": "the red car"}]),
    ("don't let the car turn left", [{"op": MOD, "behaviour.turn": "straight"}]),
    ("can the bus go 10 mph slower?", [{"op": MOD, TD: "bus", SP_MODE: "delta", SP_VAL: -10.0, SP_UNIT: "mph"}]),
    ("turn the white car left at the intersection",
     [{"op": MOD, "target.description": "the white car", "behaviour.turn": "left"}]),
    ("make everyone stop", [{"op": MOD, "target.description": "everyone", TG: True}]),
    ("add some barrels along the curb", [{"op": INS, AS: "barrel", AN: 3, PR: "on_road"}]),
    ("add a bus in the oncoming lane driving towards us", [{"op": INS, PR: "in_lane", PL: "opposite"}]),
    ("make the car turn into the left lane", [{"op": MOD, "behaviour.lane_change": "left", "behaviour.turn": None}]),
    ("the car in the left lane should stop", [{"op": MOD, "target.description": "the car in the left lane"}]),
    ("the red car: stop", [{"op": MOD, "target.description": "the red car", "behaviour.stop": "set"}]),
    ("Node 4 should stop at 3s", [{"op": MOD, "target.node_id": 4, "behaviour.stop.at_time_s": 3.0}]),
    ("make object ped_2 run across the road", [{"op": MOD, "target.object_id": "ped_2", "behaviour.gait": "run"}]),
    ("slow the white car down by 5 km/h", [{"op": MOD, TD: "white car", SP_MODE: "delta", SP_VAL: -5.0}]),
    ("make the truck go at 80% of its speed", [{"op": MOD, SP_MODE: "factor", SP_VAL: 0.8}]),
    ("bring the black SUV to a stop", [{"op": MOD, TD: "black suv", "behaviour.stop": "set"}]),
    ("make the car stop in 2 seconds", [{"op": MOD, "behaviour.stop.at_time_s": 2.0}]),
    ("have the motorcycle shadow the bus", [{"op": MOD, "behaviour.follow.description": "the bus"}]),
    ("steer the bus into the right lane", [{"op": MOD, TD: "bus", "behaviour.lane_change": "right"}]),
    ("get all the pedestrians to stop", [{"op": MOD, TG: True, "behaviour.stop": "set"}]),
    ("put a construction sign in front of the van", [{"op": INS, AC: "static", PR: "in_front_of", PA: "van"}]),
    ("insert a man crossing the road 10 m ahead",
     [{"op": INS, AC: "pedestrian", PR: "in_front_of", PD: 10.0, "behaviour.cross_street": True}]),
    ("make the van follow the car in front", [{"op": MOD, "behaviour.follow.description": "the car in front"}]),
    ("put a barrier on the right side of the lane", [{"op": INS, AS: "barrier", PR: "on_road"}]),
    ("add a stop sign at the corner", [{"op": INS, AS: "stop sign", AC: "static", PR: "on_sidewalk"}]),
    ("put a row of cones along the left lane", [{"op": INS, AN: 5, PR: "in_lane", PL: "left", "behaviour": None}]),
    ("add a person standing on the corner",
     [{"op": INS, AC: "pedestrian", PR: "on_sidewalk", "behaviour.stop": "set"}]),
    ("make the man on the left stop walking", [{"op": MOD, "behaviour.stop": "set", "behaviour.gait": None}]),
    ("make the parked car pull out and drive away",
     [{"op": MOD, "behaviour.longitudinal": "accelerate", "behaviour.stop": None}]),
    ("have the truck in front of us brake suddenly",
     [{"op": MOD, "target.description": "the truck in front of us", "behaviour.longitudinal": "brake_hard"}]),
    ("have the pedestrian wait 2 seconds and then cross",
     [{"op": MOD, "behaviour.start_time_s": 2.0, "behaviour.cross_street": True}]),
]

#: Phrasing families an independent prompt generator used (variants of them, not its prompts).
FAMILIES: list[tuple[str, list[dict[str, Any]]]] = [
    # "and" between garments / colours stays in the noun phrase
    ("add a cyclist in a yellow jacket and black shorts on the road 5 m ahead",
     [{"op": INS, "asset.description": "a cyclist in a yellow jacket and black shorts", AK: "yellow", PR: "on_road",
       PD: 5.0}]),
    ("remove the woman in a blue coat and white trousers",
     [{"op": REM, "target.description": "the woman in a blue coat and white trousers"}]),
    ("the man wearing a black jacket and grey jeans should stop",
     [{"op": MOD, "target.description": "the man wearing a black jacket and grey jeans", "behaviour.stop": "set"}]),
    ("add a cone and a barrier in front of the van", [{"op": INS, AS: "traffic cone"}, {"op": INS, AS: "barrier"}]),
    # relative clauses and participles stay in the target / anchor description
    ("the woman who's on the crosswalk should run",
     [{"op": MOD, "target.description": "the woman who is on the crosswalk", "behaviour.gait": "run"}]),
    ("make the van which is in the left lane slow down",
     [{"op": MOD, "target.description": "the van which is in the left lane", "behaviour.longitudinal": "decelerate"}]),
    ("put a cone 2 m behind the taxi that is stopped at the light",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the taxi that is stopped at the light", PD: 2.0,
       "behaviour": None}]),
    ("add a barrel on the right side of the truck parked by the curb",
     [{"op": INS, PR: "right_of", "placement.anchor.description": "the truck parked by the curb"}]),
    ("put a barrier next to the bus making a left turn",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the bus making a left turn", "behaviour": None}]),
    ("the pedestrian in a red top and black pants who is standing on the curb should walk across the street",
     [{"op": MOD, TD: "black pants who is standing on the curb", "behaviour.cross_street": True}]),
    ("delete the man in a grey hoodie sitting and waiting on the bench",
     [{"op": REM, "target.description": "the man in a grey hoodie sitting and waiting on the bench"}]),
    # lanes
    ("add a van in the opposing lane 40 m ahead", [{"op": INS, PR: "in_lane", PL: "opposite", PD: 40.0}]),
    ("put a truck 20 m ahead in the lane of the oncoming traffic", [{"op": INS, PR: "in_lane", PL: "opposite"}]),
    ("put a car one lane over to the right 20 m ahead", [{"op": INS, PR: "in_lane", PL: "right", PD: 20.0}]),
    ("add a truck in my lane 30 meters up ahead", [{"op": INS, PR: "in_lane", PL: "same", PD: 30.0}]),
    ("add a taxi in the lane we are in, 15 m ahead", [{"op": INS, PR: "in_lane", PL: "same", PD: 15.0}]),
    ("place a bus 15 m behind the red car in the left lane",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the red car in the left lane", PL: None}]),
    # verbs and idioms
    ("the man should start jogging", [{"op": MOD, "behaviour.gait": "run"}]),
    ("the woman in the green dress should begin running", [{"op": MOD, "behaviour.gait": "run"}]),
    ("add a man sauntering along the sidewalk 5 m ahead", [{"op": INS, PR: "on_sidewalk", "behaviour.gait": "walk"}]),
    ("delay the white van that is waiting at the junction by 3 seconds",
     [{"op": MOD, "target.description": "the white van that is waiting at the junction", "behaviour.delay_s": 3.0}]),
    ("the girl should cross over to the other side of the road", [{"op": MOD, "behaviour.cross_street": True}]),
    ("make the child stand still", [{"op": MOD, "behaviour.stop": "set"}]),
    ("the taxi should pull up and stop", [{"op": MOD, TD: "taxi", "behaviour.stop": "set"}]),
    ("take the red truck parked near the bus out of the scene",
     [{"op": REM, "target.description": "the red truck parked near the bus"}]),
    ("set the speed of the black van to 20 km/h",
     [{"op": MOD, TD: "black van", SP_MODE: "absolute", SP_VAL: 20.0, SP_UNIT: "km/h"}]),
    ("the bus should reduce its speed to 30 km/h", [{"op": MOD, SP_MODE: "absolute", SP_VAL: 30.0}]),
    ("add a line of 6 cones in the right lane", [{"op": INS, AN: 6, PR: "in_lane", PL: "right"}]),
    ("put a row of three barriers 10 m ahead", [{"op": INS, AS: "barrier", AN: 3, PD: 10.0}]),
    # a relative clause / participle before a verb phrase ends where the verb phrase starts
    ("make the silver van that is at the junction lower its speed",
     [{"op": MOD, "target.description": "the silver van that is at the junction",
       "behaviour.longitudinal": "decelerate"}]),
    ("have the taxi which is turning right slow down",
     [{"op": MOD, "target.description": "the taxi which is turning right", "behaviour.longitudinal": "decelerate"}]),
    ("tell the truck that is going to the intersection to decrease its speed",
     [{"op": MOD, "target.description": "the truck that is going to the intersection",
       "behaviour.longitudinal": "decelerate"}]),
    ("get the bus that is waiting at the light to increase its speed",
     [{"op": MOD, "target.description": "the bus that is waiting at the light",
       "behaviour.longitudinal": "accelerate"}]),
    ("the van that's behind us should lower its speed",
     [{"op": MOD, "target.description": "the van that is behind us", "behaviour.longitudinal": "decelerate"}]),
    ("let the truck that is parked on the left drive off",
     [{"op": MOD, "target.description": "the truck that is parked on the left",
       "behaviour.longitudinal": "accelerate"}]),
    ("have the white car making a left on our right do an emergency stop",
     [{"op": MOD, "target.description": "the white car making a left on our right",
       "behaviour.longitudinal": "brake_hard", "behaviour.stop": "set"}]),
    ("have the bus waiting to turn left stop", [{"op": MOD, "target.description": "the bus waiting to turn left",
                                                  "behaviour.stop": "set", "behaviour.turn": None}]),
    ("make the car that is on the left turn right", [{"op": MOD, "target.description": "the car that is on the left",
                                                       "behaviour.turn": "right"}]),
    # intersection words
    ("have the bus turn left at the next junction", [{"op": MOD, TD: "bus", "behaviour.turn": "left"}]),
    ("make the sedan that is slowing down take a left at the crossroad",
     [{"op": MOD, "target.description": "the sedan that is slowing down", "behaviour.turn": "left"}]),
    ("the van should turn right at the crossing", [{"op": MOD, "behaviour.turn": "right",
                                                   "behaviour.cross_street": False}]),
    ("stop the taxi before the crossroads", [{"op": MOD, "behaviour.stop.before": "intersection"}]),
    # an ego-relative location after an anchor describes the anchor (an insert has one placement relation)
    ("Add a white pickup behind the white van to the left of the ego car.",
     [{"op": INS, AS: "pickup truck", PR: "behind",
       "placement.anchor.description": "the white van to the left of the ego car", "behaviour": None}]),
    ("Put a yellow barrel in front of the grey SUV on the right-hand side.",
     [{"op": INS, AS: "barrel", PR: "in_front_of",
       "placement.anchor.description": "the grey suv on the right-hand side"}]),
    ("put a cone behind the black sedan on the left hand side",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the black sedan on the left-hand side"}]),
    ("make the silver car on the right hand side turn left",
     [{"op": MOD, "target.description": "the silver car on the right-hand side", "behaviour.turn": "left"}]),
    ("delete the grey car on the left hand side of the road",
     [{"op": REM, "target.description": "the grey car on the left-hand side of the road"}]),
    ("insert a cone next to the silver car on our left",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the silver car on our left"}]),
    ("add a pedestrian in front of the bus on the right side",
     [{"op": INS, AC: "pedestrian", PR: "in_front_of", "placement.anchor.description": "the bus on the right side"}]),
    ("place a barrier beside the van on my right",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the van on my right"}]),
    ("add a taxi behind the car to our left", [{"op": INS, PR: "behind", PA: "the car to our left"}]),
    ("put a barrel next to the truck on the right of us",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the truck on the right of us"}]),
    ("add a van 10 m behind the bus ahead of us on the right",
     [{"op": INS, PR: "behind", PD: 10.0, "placement.anchor.description": "the bus ahead of us on the right"}]),
    ("move the van behind the bus on the left",
     [{"op": MOD, TD: "the van", PR: "behind", "placement.anchor.description": "the bus on the left"}]),
    ("put a cone in front of the van to the left of the bus",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the van to the left of the bus"}]),
    ("add a cone on our left", [{"op": INS, PR: "left_of", "placement.anchor": None}]),
    # a participle or "that is ..." after an anchor describes it; a static object cannot take it as behaviour
    ("Put a traffic cone right behind the red saloon car at the intersection continuing straight.",
     [{"op": INS, AS: "traffic cone", PR: "behind",
       "placement.anchor.description": "the red saloon car at the intersection continuing straight",
       "behaviour": None}]),
    # participles joined by "and" go on describing the anchor; an area after them is the anchor's, not the relation
    ("Put a woman wearing a green jacket and blue jeans on the right side of the pedestrian in a green shirt "
     "standing and waiting on the sidewalk ahead of the ego car.",
     [{"op": INS, PR: "right_of", "placement.anchor.description":
       "the pedestrian in a green shirt standing and waiting on the sidewalk ahead of the ego car",
       "behaviour": None}]),
    ("put a cone behind the truck parked and waiting at the curb",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the truck parked and waiting at the curb"}]),
    ("add a car behind the bus and make it turn left",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus", "behaviour.turn": "left"}]),
    ("put a barrier behind the truck that is stopped at the light",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the truck that is stopped at the light"}]),
    ("place a red car behind the van driving in the opposite lane",
     [{"op": INS, AK: "red", PR: "behind", "placement.anchor.description": "the van driving in the opposite lane",
       "behaviour": None}]),
    ("add a car behind the bus turning left at the intersection",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus turning left at the intersection",
       "behaviour": None}]),
    ("add a taxi next to the van which is waiting at the junction",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the van which is waiting at the junction",
       "behaviour": None}]),
    ("put a cone behind the bus that turns left",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus that turns left", "behaviour": None}]),
    ("add a cone in front of the car coming towards us",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the car coming towards us"}]),
    ("add a barrier next to the man not moving",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the man not moving", "behaviour": None}]),
    ("add a man in a green jacket next to the grey vehicle not moving to the left of the ego car",
     [{"op": INS, PR: "next_to", "behaviour": None,
       "placement.anchor.description": "the grey vehicle not moving to the left of the ego car"}]),
    # ... while a verb phrase of its own, a speed, or a motion the anchor cannot do is the inserted object's
    ("add a car behind the bus that turns left",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus", "behaviour.turn": "left"}]),
    ("add a car behind the truck which should turn right",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the truck", "behaviour.turn": "right"}]),
    ("add a car in our lane driving at 30 km/h",
     [{"op": INS, PR: "in_lane", PL: "same", SP_VAL: 30.0, SP_UNIT: "km/h"}]),
    ("add a van 10 m behind the bus on our right driving at 40 km/h",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus on our right", SP_VAL: 40.0}]),
    ("add a car behind the bus going 30 km/h",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the bus", SP_VAL: 30.0}]),
    ("add a pedestrian in front of the bus crossing the road",
     [{"op": INS, AC: "pedestrian", PR: "in_front_of", "placement.anchor.description": "the bus",
       "behaviour.cross_street": True}]),
    ("add a pedestrian in front of the car waiting to cross",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the car", "behaviour.cross_street": True}]),
    ("add a woman next to the man waiting to cross",
     [{"op": INS, PR: "next_to", "placement.anchor.description": "the man waiting to cross", "behaviour": None}]),
    ("add a car next to the pedestrian turning left",
     [{"op": INS, AC: "vehicle", PR: "next_to", "placement.anchor.description": "the pedestrian",
       "behaviour.turn": "left"}]),
    # "us" ends the noun phrase: "back up" after it is the verb
    ("Make the red SUV ahead of us back up.",
     [{"op": MOD, TD: "the red suv ahead of us", "behaviour.reverse": True}]),
    # "away from the crosswalk" is where not to cross (jaywalking), not how far ahead to put the person
    ("Insert a person wearing a white jacket crossing the street away from the crosswalk, 10 meters ahead.",
     [{"op": INS, AC: "pedestrian", PR: "in_front_of", "placement.distance_m": 10.0,
       "behaviour.cross_street": True, "behaviour.jaywalk": True}]),
    # "standing still in traffic" is a car's state as much as a person's: it stays with the car it follows
    ("Put a person in a white sweater beside the white vehicle standing still in traffic.",
     [{"op": INS, AC: "pedestrian", PR: "next_to",
       "placement.anchor.description": "the white vehicle standing still in traffic", "behaviour": None}]),
    ("add a car behind the van parked on the right and make it turn left",
     [{"op": INS, PR: "behind", "placement.anchor.description": "the van parked on the right",
       "behaviour.turn": "left"}]),
    # "not moving" in a noun phrase describes a stationary object; it is no negated edit
    ("Make the person in a red jacket and beige trousers not moving cross the street.",
     [{"op": MOD, "target.description": "the person in a red jacket and beige trousers not moving",
       "behaviour.cross_street": True}]),
    ("make the man who isn't moving walk across the road",
     [{"op": MOD, "target.description": "the man who is not moving", "behaviour.cross_street": True}]),
    ("the pedestrian not walking should run", [{"op": MOD, TD: "the pedestrian not walking", "behaviour.gait": "run"}]),
    ("remove the woman not moving", [{"op": REM, "target.description": "the woman not moving"}]),
    ("add a person not moving on the sidewalk", [{"op": INS, AC: "pedestrian", PR: "on_sidewalk",
                                                  "behaviour.stop": "set"}]),
    # sector phrases stay in a target's description
    ("remove the car on the left-hand side", [{"op": REM, "target.description": "the car on the left-hand side"}]),
    ("make the cyclist on our right stop", [{"op": MOD, TD: "the cyclist on our right", "behaviour.stop": "set"}]),
    ("have the car parked on the right pull out",
     [{"op": MOD, "target.description": "the car parked on the right", "behaviour.longitudinal": "accelerate"}]),
    # "standing still" after a vehicle anchor is the anchor's (a stationary vehicle), not the placed person's
    ("Add a man wearing a yellow hoodie 1 meter right of the grey vehicle standing still.",
     [{"op": INS, AC: "pedestrian", PR: "right_of", PD: 1.0,
       "placement.anchor.description": "the grey vehicle standing still", "behaviour": None}]),
    ("add a woman in front of the van sitting still",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the van sitting still", "behaviour": None}]),
    # "bring X to a halt / stop / standstill" is a stop; a describing clause before it keeps only the description
    ("Bring the silver car turning to a halt.",
     [{"op": MOD, "target.description": "the silver car turning", "behaviour.stop": "set"}]),
    ("bring the gray vehicle that's heading straight on to a complete standstill",
     [{"op": MOD, "target.description": "the gray vehicle that is heading straight on", "behaviour.stop": "set"}]),
    ("bring the bus turning left to a stop before the crosswalk",
     [{"op": MOD, TD: "the bus turning left", "behaviour.stop.before": "crosswalk"}]),
    # ... but "coming / braking to a halt" describes the object itself
    ("Place a traffic cone 1 meter ahead of the silver hatchback braking to a halt.",
     [{"op": INS, PR: "in_front_of", "placement.anchor.description": "the silver hatchback braking to a halt",
       "behaviour": None}]),
    ("Delay the red pickup truck coming to a stop on my left by 2 secs.",
     [{"op": MOD, TD: "the red pickup truck coming to a stop on my left", "behaviour.delay_s": 2.0}]),
    ("Put a traffic cone right behind the sport utility vehicle that is pulling up to a stop to our left.",
     [{"op": INS, PR: "behind",
       "placement.anchor.description": "the sport utility vehicle that is pulling up to a stop to our left"}]),
    # the replaced object's description may hold "by" itself
    ("Swap the sedan parked by the side of the road for a yellow hatchback.",
     [{"op": "replace", TD: "the sedan parked by the side of the road", "asset.color": "yellow"}]),
    # a relative speed after a describing clause is the edit, not part of the description
    ("Make the yellow hatchback which is going straight 10 km/h faster.",
     [{"op": MOD, "target.description": "the yellow hatchback which is going straight", SP_MODE: "delta",
       SP_VAL: 10.0, SP_UNIT: "km/h"}]),
    ("make the car turning left twice as fast",
     [{"op": MOD, "target.description": "the car turning left", SP_MODE: "factor", SP_VAL: 2.0}]),
    ("make the van that is driving in the right lane 20% slower",
     [{"op": MOD, "target.description": "the van that is driving in the right lane", SP_MODE: "factor",
       SP_VAL: 0.8}]),
    # "before it reaches / getting to the crosswalk" is where to stop, also after a describing clause
    ("Stop the silver sedan which is continuing straight in the oncoming lane before it reaches the crosswalk.",
     [{"op": MOD, "target.description": "the silver sedan which is continuing straight in the oncoming lane",
       "behaviour.stop.before": "crosswalk"}]),
    ("the van should stop before it gets to the intersection",
     [{"op": MOD, "target.description": "the van", "behaviour.stop.before": "intersection"}]),
    ("stop the car before reaching the crosswalk",
     [{"op": MOD, "target.description": "the car", "behaviour.stop.before": "crosswalk"}]),
    # a crossing direction after "pedestrian crossing" makes "crossing" a participle, not a crosswalk
    ("Get rid of each pedestrian crossing from the left to the right ahead of the ego car.",
     [{"op": REM, "target.description": "each pedestrian crossing from the left to the right ahead of the ego car",
       TG: True}]),
    ("remove the pedestrian crossing from right to left",
     [{"op": REM, "target.description": "the pedestrian crossing from right to left", TG: False}]),
]

TABLE = REMOVE + INSERT + REPLACE + SPEED + STOP + MOTION + PEDESTRIAN + MULTI + TYPED + FAMILIES


def test_a_corner_is_a_turn_only_when_it_is_taken() -> None:
    assert motion_kinds("standing on the corner") == {"pedestrian"}
    assert motion_kinds("waiting at the corner") == {"pedestrian"}
    assert motion_kinds("going round the corner") == {"vehicle"}
    assert motion_kinds("cornering fast") == {"vehicle"}


def test_the_table_is_large_and_distinct() -> None:
    prompts = [p for p, _ in TABLE]
    assert len(prompts) >= 150
    assert len(set(prompts)) == len(prompts)


@pytest.mark.parametrize(("prompt", "expected"), TABLE, ids=[p[:60] for p, _ in TABLE])
def test_phrasing_parses_to_the_expected_commands(prompt: str, expected: list[dict[str, Any]],
                                                  encoder: TextEncoder) -> None:
    program = parse_prompt(prompt, encoder=encoder)
    assert program.prompt == prompt
    assert not program_mismatches(program.commands, expected), program_mismatches(program.commands, expected)


REFUSALS: list[tuple[str, str, tuple[str, ...]]] = [
    ("make the car fly", "unsupported", ("'fly'",)),
    ("paint the sky red", "unsupported", ("paint",)),
    ("turn the bus into a dragon", "unsupported", ("dragon",)),
    ("make it rain", "unsupported", ("'rain'",)),
    ("", "unsupported", ("empty",)),
    ("   ", "unsupported", ("empty",)),
    ("hello there", "unsupported", ("hello",)),
    ("what is the weather like", "unsupported", ("weather",)),
    ("make the pedestrian change lanes to the left", "wrong_category", ("pedestrian", "changing lanes")),
    ("make the pedestrian change lanes", "wrong_category", ("pedestrian", "changing lanes")),
    ("make the traffic cone turn left", "wrong_category", ("static", "cannot move")),
    ("make the car jaywalk", "wrong_category", ("vehicle", "jaywalking")),
    ("make the cone drive at 10 km/h", "wrong_category", ("static",)),
    ("make the pedestrian reverse", "wrong_category", ("pedestrian", "reverse")),
    ("make the barrier follow the bus", "wrong_category", ("static",)),
    ("remove the sky", "unsupported", ("not an object",)),
    ("remove the crossroads", "unsupported", ("not an object",)),
    ("make the ego car stop", "unsupported", ("ego",)),
    ("make the car go 500 km/h", "invalid_command", ("speed",)),
    ("add a unicorn next to the bus", "unsupported", ("unicorn",)),
    ("make the truck explode", "unsupported", ("explode",)),
    ("add a cone between the bus and the truck", "unsupported", ("between",)),
    ("replace the van", "unsupported", ("replace",)),
    ("make the car stop and fly", "unsupported", ("'fly'",)),
    ("make the car do a u-turn", "unsupported", ("U-turn",)),
    ("make the car change lanes", "unsupported", ("left", "right")),
    ("make the bus not stop", "unsupported", ("negated",)),
    ("the red car", "unsupported", ("red car",)),
    ("make the car grow wings", "unsupported", ("grow wings",)),
    ("remove it", "unsupported", ("'it'",)),
    ("add 30 cones", "unsupported", ("at most 20",)),
    ("Spawn a police car 20m behind us in the right lane", "unsupported", ("lane placement",)),
    ("add a car in the right lane behind the bus", "unsupported", ("lane placement",)),
    ("make the car not move", "unsupported", ("negated",)),
    ("do not make the bus stop", "unsupported", ("negated",)),
]


@pytest.mark.parametrize(("prompt", "reason", "words"), REFUSALS, ids=[p[:50] or "empty" for p, _, _ in REFUSALS])
def test_refusals_say_what_was_not_understood(prompt: str, reason: str, words: tuple[str, ...],
                                              encoder: TextEncoder) -> None:
    with pytest.raises(EditRefused) as info:
        parse_prompt(prompt, encoder=encoder)
    message = str(info.value)
    assert info.value.reason == reason, message
    for word in words:
        assert word.lower() in message.lower(), message
    if reason == "unsupported":
        assert SUPPORTED in message  # ... and what is supported
        assert "insert, remove, replace" in message


@pytest.mark.parametrize(("prompt", "expected"), [
    ("yank the van out of the scene", [{"op": REM, "target.description": "the van"}]),
    ("make the pedestrian tiptoe across the road", [{"op": MOD, "behaviour.cross_street": True}]),
    ("make the bus come to rest", [{"op": MOD, "behaviour.stop": "set"}]),
    ("make the truck screech to a stop", [{"op": MOD, "behaviour.stop": "set"}]),
    ("banish the silver SUV", [{"op": REM, TD: "silver suv"}]),
])
def test_unknown_verbs_go_to_the_nearest_supported_intent(prompt: str, expected: list[dict[str, Any]],
                                                          encoder: TextEncoder) -> None:
    program = parse_prompt(prompt, encoder=encoder)
    assert not program_mismatches(program.commands, expected), program_mismatches(program.commands, expected)


class _NoEncoder:
    """An encoder that must not be called: prompts the rules cover need no E5."""

    name = "must-not-be-called"
    dim = 384

    def encode_queries(self, texts: list[str]) -> np.ndarray:
        raise AssertionError(f"E5 called for {texts}")

    encode_passages = encode_queries


@pytest.mark.parametrize("prompt", ["remove the white van and make the red car stop",
                                    "add a row of orange cones in the ego lane 20 m ahead",
                                    "make the taxi 10 km/h slower", "make the pedestrian cross the street",
                                    "bring the silver car to a halt"])
def test_rule_covered_prompts_do_not_embed(prompt: str) -> None:
    assert parse_prompt(prompt, encoder=_NoEncoder()).commands


class _CountingEncoder:
    def __init__(self, inner: TextEncoder) -> None:
        self.inner, self.name, self.dim = inner, "counting-" + inner.name, inner.dim
        self.passage_calls = 0
        self.query_calls = 0

    def encode_queries(self, texts: list[str]) -> np.ndarray:
        self.query_calls += 1
        return self.inner.encode_queries(texts)

    def encode_passages(self, texts: list[str]) -> np.ndarray:
        self.passage_calls += 1
        return self.inner.encode_passages(texts)


def test_intent_prototypes_are_embedded_once(encoder: TextEncoder) -> None:
    counting = _CountingEncoder(encoder)
    parse_prompt("yank the van out of the scene", encoder=counting)
    parse_prompt("make the bus come to rest", encoder=counting)
    assert counting.passage_calls == 1
    assert counting.query_calls == 2


def test_programs_round_trip_through_the_json_schema(encoder: TextEncoder) -> None:
    program = parse_prompt("remove the white van, then add a cone 2 m to the left of the bus and make the "
                           "red car stop behind it", encoder=encoder)
    assert program_from_json(program_to_json(program)) == program
    assert [c.op for c in program.commands] == ["remove", "insert", "modify"]
    assert program.commands[2].behaviour is not None and program.commands[2].behaviour.stop is not None
    behind = program.commands[2].behaviour.stop.behind
    assert behind is not None and behind.description == "the bus"
    assert "red car" in program.commands[2].note
