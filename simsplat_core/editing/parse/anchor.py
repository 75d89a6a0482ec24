"""Whose words follow an anchor's noun phrase: more of the anchor's description, or the placed object's own.

    qualifier_length("to the left of the ego car".split(), anchor="the white van", mover="vehicle")  # 7
    qualifier_length("driving at 30 km/h".split(), anchor="the bus", mover="vehicle")                # 0

An insert has one placement relation ("behind the white van"); what follows the anchor's head noun phrase
is read by the grounding parser's own spans (``grounding.parse.find_spans``: the sector, map-context and motion
phrases the ``QueryEngine`` grounds) and belongs to the anchor ("the white van *to the left of the ego
car*", "the red car *at the intersection continuing straight*", "the bus *that is waiting at the light*"),
except:

* a relative clause with a verb of its own ("*that turns left*", "*which should stop*") is the placed
  object's behaviour -- unless the placed object cannot move (a cone), when it can only describe the anchor;
* a motion phrase of a kind the anchor cannot do and the placed object can ("add a pedestrian in front of
  the bus *crossing the road*") is the placed object's;
* a motion phrase that goes on with words the grounding does not read ("*driving at 30 km/h*", "*going
  slowly*") is the placed object's predicate.

A location phrase relating the anchor to another object stays with it too ("the van *to the left of the
bus*"): the grounding engine reads what it can of it.

Everything a static object is placed next to is described, so "put a cone behind the bus turning left" never
reads as a cone turning.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.language.grounding.lexicon import MOTION_KEYWORDS
from simsplat_core.language.grounding.parse import find_spans, normalise, parse_query
from simsplat_core.scenario.vocabulary import MOTION_VOCABULARIES

#: Relative pronouns that start a clause about the noun before them.
RELATIVE_PRONOUNS = ("that", "which", "who")
#: Verbs that make a relative clause a description ("that *is* parked"), not an instruction ("that turns").
_COPULAS = ("is", "are", "was", "were")
#: Span kinds of the grounding parser that name where an object is, and those that name how it moves.
_LOCATION_SPANS = ("sector", "context")
_MOTION_SPANS = ("motion", "direction")
#: The agent kind of an object that cannot move.
STATIC = "static"


def agent_kind(query_categories: Sequence[str]) -> str | None:
    """Agent kind of a grounding query's categories ("vehicle" / "pedestrian" / "static"), None if unknown."""
    if not query_categories:
        return None
    kinds = {lex.ASSET_CATEGORY[c] for c in query_categories}
    return kinds.pop() if len(kinds) == 1 else None


def motion_kinds(phrase: str) -> frozenset[str]:
    """Agent kinds that can do every motion the phrase names: for each motion keyword it holds, a kind whose
    vocabulary has one of the keyword's classes ("crossing the road" -> pedestrian, "waiting to cross" ->
    pedestrian, "stopped at the light" -> vehicle and pedestrian). A keyword found only inside a longer one's
    words is that one's ("standing still" is stationary, for vehicles too, not a pedestrian's "stand")."""
    found = [(m.span(), named) for rx, named in MOTION_KEYWORDS if (m := re.search(rx, phrase)) is not None]
    kinds = frozenset(MOTION_VOCABULARIES)
    for (a, b), named in found:
        if any(c <= a and b <= d and d - c > b - a for (c, d), _ in found):
            continue
        kinds &= {kind for kind, vocabulary in MOTION_VOCABULARIES.items() if set(named) & set(vocabulary.names)}
    return kinds


def _span_at(words: Sequence[str], i: int) -> tuple[str, int] | None:
    """``(kind, words it takes)`` of the grounding span that starts at ``words[i]``, or None."""
    plain = []
    for word in words[i:]:
        if normalise(word) != word:  # a unit, a coordinate, punctuation: no description goes past it
            break
        plain.append(word)
    text = " ".join(plain)
    span = next((s for s in find_spans(text) if s.start == 0), None)
    return (span.kind, len(text[: span.end].split())) if span is not None else None


def _object_after(words: Sequence[str], i: int) -> int:
    """End of another object's noun phrase a location phrase ending before ``words[i]`` relates to ("to the
    left *of the bus*", "behind *the truck*"); ``i``: none."""
    j = i + 1 if i < len(words) and words[i] == "of" else i
    if j >= len(words) or not chunks.match(words, j, lex.DETERMINERS):
        return i
    end = chunks.chunk_np(words, j, "inner")
    return end if end > j else i


def _continues(words: Sequence[str], i: int) -> bool:
    """Whether words after a motion phrase go on with its verb phrase ("driving *at 30 km/h*")."""
    return (i < len(words) and words[i] not in chunks.PUNCT and words[i] not in lex.SOFT_BREAKS
            and words[i] not in RELATIVE_PRONOUNS)


def qualifier_length(words: Sequence[str], *, anchor: str, mover: str | None) -> int:
    """How many of ``words`` (canonical words right after an anchor's noun phrase, ``editing.parse.chunks`` "anchor"
    mode) describe the anchor (module docstring).

    Args:
        anchor: the anchor's noun phrase ("the white van").
        mover: agent kind of the object being placed ("vehicle", "pedestrian", "static"; None: unknown).
    """
    anchor_kind = agent_kind(parse_query(anchor).categories)
    movable = mover != STATIC
    j = 0
    motion_start: int | None = None  # where the last motion phrase taken began
    while j < len(words):
        if words[j] in RELATIVE_PRONOUNS:
            copular = j + 1 < len(words) and words[j + 1] in _COPULAS
            if movable and not copular:
                break  # "that turns left": the placed object's behaviour
            j = chunks.clause_tail(words, j + (2 if copular else 1), relative=True)
            motion_start = None
            continue
        if (words[j] == "and" and j and j + 1 < len(words)
                and (chunks.is_participle(words[j + 1]) or _span_at(words, j + 1))):
            j += 1  # "standing *and* waiting on the sidewalk": the description goes on
            continue
        if words[j] == "not" and j + 1 < len(words) and chunks.is_participle(words[j + 1]):
            j += 2  # "the grey car *not moving* to the left of us": a state of the anchor, not a motion to give
            motion_start = None
            continue
        if words[j] == "to" and j and words[j - 1] in chunks.TO_KEEPERS and _span_at(words, j + 1):
            j += 1  # "waiting to turn left", "going to the junction"
            continue
        found = _span_at(words, j)
        if found is not None and found[0] in _LOCATION_SPANS:
            j = _object_after(words, j + found[1])  # "to the left of the ego car", "on the left *of the bus*"
            motion_start = None
            continue
        if found is not None and movable:
            kinds = motion_kinds(" ".join(words[j : j + found[1]]))
            if mover in kinds and anchor_kind is not None and anchor_kind not in kinds:
                break  # "in front of the bus crossing the road": buses do not cross
            motion_start, j = j, j + found[1]
            continue
        if found is not None or chunks.is_participle(words[j]):  # what the grounding does not read still describes
            j = chunks.clause_tail(words, j + 1, relative=False)
            motion_start = None
            continue
        break
    if movable and motion_start is not None and _continues(words, j):
        return motion_start  # "driving at 30 km/h": the placed object's predicate
    return j
