"""The behaviour vocabulary is spelled once: every table keyed by its classes has an entry for each class."""

from __future__ import annotations

import ast
from pathlib import Path

import simsplat_core
from simsplat_core.eval import motion as motion_eval
from simsplat_core.eval.grounding import paraphrases
from simsplat_core.language.grounding import lexicon
from simsplat_core.scenario import vocabulary as voc

CORE = Path(simsplat_core.__file__).resolve().parent


def test_constants_name_the_vocabulary_classes() -> None:
    for vocabulary in (voc.VEHICLE_MOTION, voc.PEDESTRIAN_MOTION, voc.LOCATION_SECTOR, voc.LOCATION_CONTEXT):
        for name in vocabulary.names:
            assert getattr(voc, name.upper()) == name
    assert set(voc.MOTION_VOCABULARIES) == {voc.VEHICLE, voc.PEDESTRIAN}
    assert len(set(voc.MOTION_CLASSES)) == len(voc.MOTION_CLASSES)


def test_every_class_has_its_paraphrases_and_keywords() -> None:
    for kind, vocabulary in voc.MOTION_VOCABULARIES.items():
        for name in vocabulary.names:
            term = paraphrases.EXACT_TERM[name]
            assert paraphrases.MOTION_TERMS[term][0] == kind and name in paraphrases.MOTION_TERMS[term][1]
    assert set(paraphrases._SECTOR) == set(voc.LOCATION_SECTOR.names)
    assert set(paraphrases._CONTEXT) <= set(voc.LOCATION_CONTEXT.names)
    keyword_classes = {c for _, classes in lexicon.MOTION_KEYWORDS for c in classes}
    assert keyword_classes == set(voc.MOTION_CLASSES) - set(lexicon.CROSSING_CLASSES) | {voc.CROSSING}
    assert {name for name, _ in lexicon.SECTOR_KEYWORDS} == set(voc.LOCATION_SECTOR.names)
    assert {name for name, _ in lexicon.CONTEXT_KEYWORDS} == set(voc.LOCATION_CONTEXT.names)
    assert set(motion_eval.WORLD_MOTION.values()) <= set(voc.MOTION_CLASSES)
    assert set().union(*motion_eval.WORLD_BEHAVIOUR.values()) <= set(voc.MOTION_CLASSES)


def test_no_module_spells_a_class_outside_the_vocabulary() -> None:
    """String literals equal to a class name appear only in scenario/vocabulary.py (captions excepted:
    their words are caption text, e.g. "parked", that happens to equal a class name)."""
    names = set(voc.MOTION_CLASSES + voc.LOCATION_CLASSES)
    allowed = {CORE / "scenario" / "vocabulary.py", CORE / "world" / "captions.py", CORE / "world" / "behaviors.py",
               CORE / "world" / "agents.py", CORE / "eval" / "grounding" / "baselines.py", CORE / "eval" / "motion.py"}
    offenders = []
    for path in sorted(CORE.rglob("*.py")):
        if path in allowed:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                offenders.append(f"{path.relative_to(CORE)}:{node.lineno} {node.value!r}")
    assert not offenders, offenders
