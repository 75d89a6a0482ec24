"""Clauses -> edit commands: which form a clause has, who its subject is, and what it asks.

Forms, tried in order on each clause (``editing.parse.chunks.split_clauses``):

1. replace -- "replace X with Y", "swap X for Y", "turn/change X into Y", "put Y instead of X", "X should be Y";
2. remove -- a remove verb and its objects ("delete the bus and the truck", "take the van out");
3. insert -- an insert verb and an indefinite noun phrase ("add a cone", "put two barriers ...", "there
   should be a taxi ..."), then a placement and a behaviour ("... crossing the street");
4. causative -- "make / have / let / get X <predicate>";
5. target first -- "stop the van before the crosswalk", "slow the bus down", "move the car 5 m left of X";
6. subject first -- "the truck should drive at 15 m/s", "node 12: stop";
7. continuation -- a predicate with no subject acts on the previous one ("... and then stop");
8. an unknown verb before an object ("yank the van out of the scene") -- E5 picks the op or behaviour.

Pronouns ("it", "them") as a subject are the previous subject (an object inserted before takes the
behaviour itself: "add a blue car and make it turn left" is one insert); as the object of "follow",
"behind" or a placement they are the last object named other than the subject. Consecutive predicates
on one subject merge into one command when their fields do not clash.
"""

from __future__ import annotations

import difflib
import logging
import re
from collections.abc import Sequence

from pydantic import ValidationError

from simsplat_core.editing.behaviours.registry import INTENT_FIELDS
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.editing.parse.anchor import agent_kind
from simsplat_core.editing.parse.behaviour import parse_predicate
from simsplat_core.editing.parse.placement import PlacementParse, find_placement, parse_asset, spacing_words
from simsplat_core.editing.parse.semantic import nearest_intent
from simsplat_core.editing.parse.speed import SPEED_NOUN, SPEED_VERB
from simsplat_core.editing.parse.state import INDEFINITE, Draft, PromptState, Subject
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.grounding.parse import parse_query

logger = logging.getLogger(__name__)

#: Prepositions a target-first verb's complements start with (not part of its object).
COMPLEMENT_PREPOSITIONS = ("before", "behind", "until", "till", "to", "into", "onto", "by", "after", "at", "for",
                           "over", "from", "in front of", "ahead of")
PLACEMENT_PREPOSITIONS = (*COMPLEMENT_PREPOSITIONS, "next to", "beside", "left of", "right of", "to the left of",
                          "to the right of", "on", "in", "near", "alongside")
#: Prepositions that place an object relative to the ego ("the bus *in front of us*").
_EGO_RELATIVE = ("in front of", "ahead of", "behind", "to the left of", "to the right of", "left of", "right of",
                 "next to", "beside", "alongside")


def _ego_relative_length(tokens: Sequence[str], j: int) -> int:
    """Length of an ego-relative location phrase at ``tokens[j]`` ("in front of me", "behind the ego car"), 0."""
    k = chunks.match(tokens, j, _EGO_RELATIVE)
    if not k:
        return 0
    ego = chunks.match(tokens, j + k, lex.EGO_WORDS)
    return k + ego if ego else 0


#: Words after a removed object that add nothing ("delete the bus from the scene").
_REMOVE_TAIL = re.compile(r"(?:(?:out|away|off|completely|entirely|too|as well|also|now|for good|altogether"
                          r"|from|out of|off of|of|the|this|whole|scene|road|image|picture|video|frame|frames|world"
                          r"|simulation|sim|street|clip|sequence|log|view|map|everywhere|all)\s*)*")
#: Words an insert clause may hold that say nothing ("make a cone appear", "add a new car to the scene").
_INSERT_FILLER = frozenset("appear appears show up there here new too as well also into in the scene please "
                           "somewhere a row line road".split())
#: Clause-opening verbs a typo may be corrected to.
_KNOWN_VERBS = sorted({v for v in (*lex.REMOVE_VERBS, *lex.INSERT_VERBS, *lex.REPLACE_VERBS, *lex.CAUSATIVES,
                                   *lex.TARGET_FIRST_VERBS) if " " not in v})
_SPEED_OF = re.compile(SPEED_VERB + r" (?:the )?" + SPEED_NOUN + r" of ")
_SIDEWAYS = r"(?:over )?\d+(?:\.\d+)? m (?:to the |towards the |over to the |to its )?(?:left|right)"


class PromptParser(PromptState):
    """Reads the clauses of one prompt into :class:`Draft` s (module docstring)."""

    def clause(self, tokens: list[str]) -> None:
        self.clause_text = " ".join(tokens)
        if tokens[0] in ("can", "could", "will", "would", "should", "shall") and self._np_start(tokens, 1):
            tokens = tokens[1:]  # "can the bus go slower?"
        if tokens[0] not in _KNOWN_VERBS:
            close = difflib.get_close_matches(tokens[0], _KNOWN_VERBS, n=1, cutoff=0.8)
            if close and len(tokens[0]) > 3:
                logger.debug("reading %r as %r", tokens[0], close[0])
                tokens = [close[0], *tokens[1:]]  # a typo: "remvoe the car"
        try:
            for form in (self._speed_of, self._replace, self._remove, self._insert, self._causative, self._target_first,
                         self._subject_first, self._continuation, self._unknown_verb):
                if form(tokens):
                    return
        except ValidationError as exc:  # a value the schema does not take ("500 km/h")
            error = exc.errors()[0]
            where = ".".join(str(p) for p in error["loc"])
            raise EditRefused(f"{self.clause_text!r} asks for something out of range ({exc.title}"
                              f"{'.' + where if where else ''}: {error['msg']})", reason="invalid_command") from exc
        raise self.not_understood(self.clause_text)

    def _speed_of(self, tokens: list[str]) -> bool:
        """ "set the walking speed of the man in red to 8 km/h": the speed verb, then its owner."""
        m = _SPEED_OF.match(" ".join(tokens))
        if m is None:
            return False
        start = len(m.group(0).split())
        spans = chunks.chunk_targets(tokens, start, "target", exclude=("to", "by"))
        if not spans:
            return False
        subjects = [self._subject(tokens[a:b]) for a, b in spans]
        self._modify(subjects, [tokens[0], "its", "speed", *tokens[spans[-1][1] :]])
        return True

    def _replace(self, tokens: list[str]) -> bool:
        words = " ".join(tokens)
        forms = (
            (r"(?:replace|swap(?: out)?|exchange|switch(?: out)?|trade) (.+?) (?:with|for|by) (.+)", False),
            # the old object's description may hold "by" / "with" itself: "swap the sedan parked by the road for a van"
            (r"(?:replace|swap(?: out)?|exchange|switch(?: out)?|trade) (.+) (?:with|for|by) (.+)", False),
            (r"substitute (.+?) for (.+)", True),
            (r"(?:change|turn|convert|transform|morph|make) (.+?) into (.+)", False),
            (r"(?:change|switch) (.+?) (?:to|for) ((?:a|an|another) .+)", False),
            (r"(?:put|add|place|use|insert|have|i want|we want|spawn) (.+?) instead of (.+)", True),
            (r"instead of (.+?) ,? (?:put|add|place|use|insert|have|spawn) (.+)", False),
            (r"(.+?) (?:should be|should become|becomes|is now|will be|must be|needs to be|has to be)"
             r" (?:replaced (?:with|by) )?((?:a|an) .+)", False),
        )
        for rx, swapped in forms:
            m = re.fullmatch(rx, words)
            if not m:
                continue
            old, new = (m.group(2), m.group(1)) if swapped else (m.group(1), m.group(2))
            if not self._np_start(old.split(), 0) or old.split()[0] == "there":
                continue
            if swapped and old.split()[0] in INDEFINITE and new.split()[0] not in INDEFINITE:
                old, new = new, old  # "substitute the van for a bus"
            if self._definite(new.split(), 0) or re.search(r"\blanes?\b", new):
                continue  # "turn into the left lane" is a lane change, not a replacement
            asset = parse_asset(new.split())
            if asset.spec is None:
                if rx.startswith("(?:replace") or rx.startswith("(?:change|turn|convert"):
                    raise self.refuse(asset.refusal or f"I could not understand {new!r} as something to insert")
                continue
            subject = self._subject(old.split())
            self._add(Draft("replace", words, subject, asset=asset.spec.model_copy(update={"count": 1})))
            return True
        if tokens[0] == "replace":
            raise self.refuse(f"{words!r} does not say what to replace it with: say 'replace X with Y'")
        return False

    def _remove(self, tokens: list[str]) -> bool:
        k = chunks.match(tokens, 0, lex.REMOVE_VERBS)
        particle = False
        if not k and tokens[0] in ("take", "get", "pull", "kick", "throw", "toss", "clear", "move"):
            spans = chunks.chunk_targets(tokens, 1, "target", exclude=("out", "away", "off"))
            particle = bool(spans) and tokens[spans[-1][1] : spans[-1][1] + 1] in (["out"], ["away"], ["off"])
            k = 1 if particle else 0
        if not k or (tokens[0] == "drop" and k == 1 and len(tokens) > 1 and not self._definite(tokens, 1)):
            return False
        if tokens[0] == "cut" and tokens[1:2] == ["in"]:
            return False
        spans = chunks.chunk_targets(tokens, k, "target", exclude=("out", "away", "off", "from"))
        if not spans:
            return False
        rest = " ".join(tokens[spans[-1][1] :])
        if _REMOVE_TAIL.fullmatch(rest + " " if rest else "") is None:
            raise self.not_understood(rest)
        subjects = self.pending + [self._subject(tokens[a:b]) for a, b in spans]
        self.pending = []
        for subject in subjects:
            self._remove_subject(subject)
        return True

    def _insert(self, tokens: list[str]) -> bool:
        k = chunks.match(tokens, 0, lex.INSERT_VERBS)
        if not k or not self._indefinite_start(tokens, k):
            return False
        self._insert_items(tokens[k:])
        return True

    def _insert_items(self, tokens: list[str]) -> None:
        items: list[list[str]] = [[]]
        between = False
        for i, t in enumerate(tokens):
            between = between or t == "between"
            if t in ("and", ",") and items[-1] and not between and self._indefinite_start(tokens, i + 1):
                items.append([])
                continue
            between = between and t != "and"
            items[-1].append(t)
        first = len(self.drafts)
        for item in items:
            end = chunks.chunk_np(item, 0, "asset")
            asset = parse_asset(item[:end], item[end:])
            if asset.spec is None:
                raise self.refuse(asset.refusal or f"I could not understand {' '.join(item)!r}")
            placement_parse, residual = find_placement(spacing_words(item[end:]), self.positions,
                                                       asset.spec.category)
            subject = Subject(None, asset.spec.category, " ".join(item[:end]), inserted=len(self.drafts))
            draft = Draft("insert", " ".join(item), subject, asset=asset.spec)
            residual = [w for w in residual if w not in _INSERT_FILLER and w not in chunks.PUNCT]
            self.subject = subject
            if residual:
                parse = parse_predicate(" ".join(residual), subject.kind)
                draft.fields = self._fields(parse, subject, " ".join(residual))
            draft.placement = self._placement(placement_parse, subject) if placement_parse else None
            self.drafts.append(draft)
        last = next((d.placement for d in reversed(self.drafts[first:]) if d.placement is not None), None)
        for draft in self.drafts[first:]:
            draft.placement = draft.placement or last

    def _causative(self, tokens: list[str]) -> bool:
        negated = chunks.match(tokens, 0, ("do not let", "never let", "do not allow", "do not make"))
        k = negated or chunks.match(tokens, 0, lex.CAUSATIVES)
        if not k or not self._np_start(tokens, k):
            return False
        spans = chunks.chunk_targets(tokens, k, "target")
        if not spans:
            return False
        j = spans[-1][1]
        j += 1 if tokens[j : j + 1] == ["to"] else 0
        if j >= len(tokens):
            raise self.refuse(f"{self.clause_text!r} does not say what {' '.join(tokens[k:j])!r} should do")
        self._modify([self._subject(tokens[a:b]) for a, b in spans], (["not"] if negated else []) + tokens[j:])
        return True

    def _target_first(self, tokens: list[str]) -> bool:
        verb = tokens[0]
        start = 2 if tokens[1:2] and tokens[1] in lex.PARTICLES else 1  # "slow down the bus"
        if verb not in lex.TARGET_FIRST_VERBS or not self._np_start(tokens, start):
            return False
        placing = verb in lex.PLACING_VERBS
        spans = chunks.chunk_targets(tokens, start, "target",
                                     exclude=PLACEMENT_PREPOSITIONS if placing else COMPLEMENT_PREPOSITIONS)
        if not spans:
            return False
        if not placing and (ego := _ego_relative_length(tokens, spans[-1][1])):
            # "stop the bus *in front of us*": where the ego is describes the bus (no stop place), and so does what
            # follows it ("the pedestrian in front of me *crossing the street*", "... *in the crosswalk*")
            spans[-1] = (spans[-1][0], chunks.post_modifiers_end(tokens, spans[-1][1] + ego, COMPLEMENT_PREPOSITIONS))
        j = spans[-1][1]
        if start == 1 and tokens[j : j + 1] and tokens[j] in lex.PARTICLES:  # "slow the bus down"
            particle, j = [tokens[j]], j + 1
        else:
            particle = tokens[1:start]
        rest = tokens[j:]
        if verb == "bring" and not re.match(r"(?:(?:down|up) )?to ", " ".join([*particle, *rest, ""])):
            return False  # "bring the van to a halt" (a stop or a speed), not "bring the taxi back"
        placement: PlacementParse | None = None
        if placing and re.fullmatch(_SIDEWAYS, " ".join(rest)):
            placing, verb = False, "shift"  # "move the car 1 m to the left": sideways, not left of the ego
        if placing:
            movers = {agent_kind(parse_query(" ".join(tokens[a:b])).categories) for a, b in spans}
            placement, rest = find_placement(rest, self.positions, movers.pop() if len(movers) == 1 else None)
            if verb in ("put", "place", "position") and placement is None and not rest:
                return False
        subjects = [self._subject(tokens[a:b]) for a, b in spans]
        predicate = rest if placing else [verb, *particle, *rest]
        self._modify(subjects, predicate, placement)
        return True

    def _subject_first(self, tokens: list[str]) -> bool:
        if not self._np_start(tokens, 0):
            return False
        spans = chunks.chunk_targets(tokens, 0, "target")
        if not spans:
            return False
        j = spans[-1][1]
        j += chunks.match(tokens, j, lex.MODALS)
        subjects = [self._subject(tokens[a:b]) for a, b in spans]
        if j >= len(tokens):
            self.pending.extend(subjects)
            return True
        self._modify(subjects, tokens[j:])
        return True

    def _continuation(self, tokens: list[str]) -> bool:
        if self.subject is None or not (tokens[0] in lex.PREDICATE_VERBS or not self._np_start(tokens, 1)):
            return False
        self._modify([self.subject], tokens, continuation=True)
        return True

    def _unknown_verb(self, tokens: list[str]) -> bool:
        if len(tokens) < 2 or not self._np_start(tokens, 1):
            return False
        spans = chunks.chunk_targets(tokens, 1, "target", exclude=COMPLEMENT_PREPOSITIONS)
        if not spans:
            return False
        end = spans[-1][1]
        probe = " ".join([tokens[0], "it", *tokens[end:]])
        match = nearest_intent(probe, self.encoder)
        if match.intent == "remove" and self._definite(tokens, 1):
            for a, b in spans:
                self._remove_subject(self._subject(tokens[a:b]))
            return True
        if match.intent == "insert" and self._indefinite_start(tokens, 1):
            self._insert_items(tokens[1:])
            return True
        if match.intent in INTENT_FIELDS and self._definite(tokens, 1):
            subjects = [self._subject(tokens[a:b]) for a, b in spans]
            for subject in subjects:
                self._merge(subject, dict(INTENT_FIELDS[match.intent]))
            return True
        raise self.not_understood(self.clause_text)
