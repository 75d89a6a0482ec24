"""Clauses -> edit commands: which form a clause has, who its subject is, and what it asks.

Forms, tried in order on each clause (``parser_chunks.split_clauses``):

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
from dataclasses import dataclass, field
from typing import Any

from pydantic import ValidationError

from simsplat_core.editing import parser_chunks as chunks
from simsplat_core.editing import parser_lexicon as lex
from simsplat_core.editing.commands import EGO, AssetSpec, Placement, TargetRef
from simsplat_core.editing.parser_behaviour import INTENT_FIELDS, PredicateParse, parse_predicate
from simsplat_core.editing.parser_placement import PlacementParse, find_placement, parse_asset, spacing_words
from simsplat_core.editing.parser_semantic import nearest_intent
from simsplat_core.editing.parser_text import number_word
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.query_parse import COLOR_SYNONYMS, NOUNS, parse_query
from simsplat_core.language.text import TextEncoder, default_text_encoder

logger = logging.getLogger(__name__)

#: Prepositions a target-first verb's complements start with (not part of its object).
COMPLEMENT_PREPOSITIONS = ("before", "behind", "until", "till", "to", "into", "onto", "by", "after", "at", "for",
                           "over", "from", "in front of", "ahead of")
PLACEMENT_PREPOSITIONS = (*COMPLEMENT_PREPOSITIONS, "next to", "beside", "left of", "right of", "to the left of",
                          "to the right of", "on", "in", "near", "alongside")
#: Words after a removed object that add nothing ("delete the bus from the scene").
_REMOVE_TAIL = re.compile(r"(?:(?:out|away|off|completely|entirely|too|as well|also|now|for good|altogether"
                          r"|from|out of|off of|of|the|this|whole|scene|road|image|picture|video|frame|frames|world"
                          r"|simulation|sim|street|clip|sequence|log|view|map|everywhere|all)\s*)*")
#: Words an insert clause may hold that say nothing ("make a cone appear", "add a new car to the scene").
_INSERT_FILLER = frozenset("appear appears show up there here new too as well also to into in the scene please "
                           "somewhere a row line road".split())
_INDEFINITE = ("a", "an", "another", "some", "one more")
#: Clause-opening verbs a typo may be corrected to.
_KNOWN_VERBS = sorted({v for v in (*lex.REMOVE_VERBS, *lex.INSERT_VERBS, *lex.REPLACE_VERBS, *lex.CAUSATIVES,
                                   *lex.TARGET_FIRST_VERBS) if " " not in v})
_SIDEWAYS = r"(?:over )?\d+(?:\.\d+)? m (?:to the |towards the |over to the |to its )?(?:left|right)"


def _category(query_categories: Sequence[str]) -> str | None:
    """Agent kind of a grounding query's categories ("vehicle" / "pedestrian" / "static"), None if unknown."""
    if not query_categories:
        return None
    kinds = {lex.ASSET_CATEGORY[c] for c in query_categories}
    return kinds.pop() if len(kinds) == 1 else None


@dataclass
class Subject:
    """Who a clause acts on: a grounded reference, or a command inserted earlier (``inserted``)."""

    ref: TargetRef | None
    kind: str | None
    label: str
    inserted: int | None = None


@dataclass
class Draft:
    """A command being built (``fields`` are ``Behaviour`` fields, ``stop`` a dict of ``StopSpec`` fields)."""

    op: str
    note: str
    subject: Subject | None = None
    asset: AssetSpec | None = None
    placement: Placement | None = None
    fields: dict[str, Any] = field(default_factory=dict)


def _is_ego(phrase: str) -> bool:
    return phrase in lex.EGO_WORDS


class PromptParser:
    """Reads the clauses of one prompt into :class:`Draft` s (module docstring)."""

    def __init__(self, prompt: str, positions: Sequence[tuple[float, float, float]],
                 encoder: TextEncoder | None) -> None:
        self.prompt = prompt
        self.positions = positions
        self._encoder = encoder
        self.drafts: list[Draft] = []
        self.subject: Subject | None = None
        self.mentions: list[Subject] = []
        self.pending: list[Subject] = []
        self.clause_text = ""

    @property
    def encoder(self) -> TextEncoder:
        if self._encoder is None:
            self._encoder = default_text_encoder()
        return self._encoder

    # ------------------------------------------------------------------------------------------- refusals

    def refuse(self, what: str, reason: str = "unsupported") -> EditRefused:
        text = what if what.endswith(".") else what + "."
        if reason == "unsupported":
            text += " " + lex.SUPPORTED
        return EditRefused(text, reason=reason)

    def not_understood(self, words: str) -> EditRefused:
        where = f" in {self.clause_text!r}" if words != self.clause_text else ""
        return self.refuse(f"I could not understand {words!r}{where}")

    # ------------------------------------------------------------------------------------------- clauses

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
            for form in (self._replace, self._remove, self._insert, self._causative, self._target_first,
                         self._subject_first, self._continuation, self._unknown_verb):
                if form(tokens):
                    return
        except ValidationError as exc:  # a value the schema does not take ("500 km/h")
            error = exc.errors()[0]
            where = ".".join(str(p) for p in error["loc"])
            raise EditRefused(f"{self.clause_text!r} asks for something out of range ({exc.title}"
                              f"{'.' + where if where else ''}: {error['msg']})", reason="invalid_command") from exc
        raise self.not_understood(self.clause_text)

    def finish(self) -> list[Draft]:
        if self.pending:
            raise self.refuse(f"I could not tell what should happen to {self.pending[0].label!r}")
        if not self.drafts:
            raise self.refuse(f"I found no edit in {self.prompt!r}")
        return self.drafts

    def _replace(self, tokens: list[str]) -> bool:
        words = " ".join(tokens)
        forms = (
            (r"(?:replace|swap(?: out)?|exchange|switch(?: out)?|trade) (.+?) (?:with|for|by) (.+)", False),
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
            if swapped and old.split()[0] in _INDEFINITE and new.split()[0] not in _INDEFINITE:
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

    def _remove_subject(self, subject: Subject) -> None:
        if subject.inserted is not None:
            raise self.refuse(f"{subject.label!r} refers to an object this prompt inserts; it cannot be removed")
        self._add(Draft("remove", self.clause_text, subject))

    def _definite(self, tokens: Sequence[str], i: int) -> bool:
        return i < len(tokens) and (tokens[i] in ("the", "this", "that", "these", "those", "all", "every", "each",
                                                  "both", "node", "object", "its", "their", "my", "our")
                                    or chunks.match(tokens, i, lex.PRONOUNS) > 0)

    def _indefinite_start(self, tokens: Sequence[str], i: int) -> bool:
        if i >= len(tokens):
            return False
        t = tokens[i]
        if t in _INDEFINITE or chunks.match(tokens, i, lex.QUANTITY_PHRASES):
            return True
        if number_word(t) is not None and not chunks.is_quantity(tokens, i):
            return True
        j = i + 1 if t in COLOR_SYNONYMS else i
        k = chunks.head_noun(tokens, j)
        return k > 0 and (" ".join(tokens[j : j + k]) in NOUNS or " ".join(tokens[j : j + k]) in lex.EXTRA_ASSET_NOUNS)

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
            placement_parse, residual = find_placement(spacing_words(item[end:]), self.positions)
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
        j = spans[-1][1]
        if start == 1 and tokens[j : j + 1] and tokens[j] in lex.PARTICLES:  # "slow the bus down"
            particle, j = [tokens[j]], j + 1
        else:
            particle = tokens[1:start]
        rest = tokens[j:]
        placement: PlacementParse | None = None
        if placing and re.fullmatch(_SIDEWAYS, " ".join(rest)):
            placing, verb = False, "shift"  # "move the car 1 m to the left": sideways, not left of the ego
        if placing:
            placement, rest = find_placement(rest, self.positions)
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

    # ------------------------------------------------------------------------------------------- parts

    def _np_start(self, tokens: Sequence[str], i: int) -> bool:
        """Whether an object's noun phrase starts at ``tokens[i]`` (not a particle, place or adverb)."""
        if i >= len(tokens):
            return False
        t = tokens[i]
        if chunks.match(tokens, i, lex.DETERMINERS) or chunks.match(tokens, i, lex.PRONOUNS):
            return not (t in ("that", "this") and i + 1 < len(tokens) and tokens[i + 1] in ("is", "was"))
        if t in ("node", "object", "obj", "everyone", "everybody", "everything") or t in COLOR_SYNONYMS \
                or chunks.match(tokens, i, lex.EGO_WORDS):
            return True
        k = chunks.head_noun(tokens, i)
        return k > 0 and (" ".join(tokens[i : i + k]) in NOUNS or " ".join(tokens[i : i + k]) in lex.EXTRA_ASSET_NOUNS)

    def _subject(self, np: Sequence[str]) -> Subject:
        """The subject a noun phrase names (pronouns resolved; ids read; the ego and non-objects refused)."""
        phrase = " ".join(np)
        if phrase in lex.PRONOUNS:
            if self.subject is None:
                rest = self.clause_text.split(phrase, 1)[-1].strip()
                if rest and not parse_predicate(rest).understood:
                    raise self.not_understood(rest)
                raise self.refuse(f"{phrase!r} in {self.clause_text!r} does not refer to anything named before: "
                                  "name the object")
            return self.subject
        if _is_ego(phrase):
            raise self.refuse("the ego vehicle cannot be edited (it can be an anchor: 'in front of us')")
        m = re.fullmatch(r"node (?:id |number |no )?(\d+)", phrase)
        if m:
            subject = Subject(TargetRef(node_id=int(m.group(1))), None, phrase)
        elif (m := re.fullmatch(r"(?:object|obj) (?:id )?(\S+)", phrase)) is not None:
            subject = Subject(TargetRef(object_id=m.group(1)), None, phrase)
        else:
            query = parse_query(phrase)
            head = next((" ".join(np[i : i + k]) for i in range(len(np)) if (k := chunks.head_noun(np, i))), "")
            if not query.categories and head in lex.NON_OBJECTS:
                raise self.refuse(f"{phrase!r} is not an object: only vehicles, pedestrians, cyclists and static "
                                  "objects (cones, barriers, signs) can be edited")
            group = query.group or phrase in ("everyone", "everybody", "everything", "all agents", "all objects")
            subject = Subject(TargetRef(description=phrase, group=group), _category(query.categories), phrase)
        self.mentions.append(subject)
        return subject

    def _reference(self, phrase: str, subject: Subject | None, *, ego_as_none: bool) -> TargetRef | None:
        """An anchor / leader reference: ego words -> None (or the ego), pronouns -> the last other object."""
        if _is_ego(phrase):
            return None if ego_as_none else TargetRef(description=EGO)
        if phrase in lex.PRONOUNS:
            own = subject.ref if subject is not None else None
            other = next((m for m in reversed(self.mentions) if m is not subject and m.ref != own), None)
            if other is None or other.ref is None:
                raise self.refuse(f"{phrase!r} in {self.clause_text!r} does not refer to an object of the scene: "
                                  "name it")
            return other.ref
        subject = self._subject(phrase.split())  # ids read, non-objects refused; noted as a mention
        if subject.ref is None:  # pragma: no cover - only pronouns resolve to inserted objects
            raise self.refuse(f"{phrase!r} cannot be an anchor")
        return subject.ref

    def _placement(self, p: PlacementParse, subject: Subject | None) -> Placement | None:
        if p.refusal:
            raise self.refuse(p.refusal)
        relation = p.relation
        if relation is None:
            if p.heading_deg is None and p.frame is None and p.distance_m is None:
                return None
            relation = "in_lane" if p.distance_m is None else "in_front_of"
        anchor = self._reference(p.anchor, subject, ego_as_none=True) if p.anchor else None
        lane = p.lane if relation == "in_lane" else None
        if relation == "in_lane" and lane is None:
            lane = "same"
        return Placement(relation=relation, anchor=anchor, distance_m=p.distance_m,  # type: ignore[arg-type]
                         lane=lane, position=p.position,  # type: ignore[arg-type]
                         heading_deg=p.heading_deg, frame=p.frame)

    def _fields(self, parse: PredicateParse, subject: Subject, words: str) -> dict[str, Any]:
        """Behaviour fields of a predicate (unknown words mapped by E5 or refused; references resolved)."""
        if parse.refusal:
            if parse.refusal_field:
                self._check_category(subject, {parse.refusal_field: True})
            raise self.refuse(parse.refusal[0].upper() + parse.refusal[1:])
        fields = dict(parse.fields)
        if parse.residual:
            match = nearest_intent(words, self.encoder)
            if fields or parse.refs or parse.op:  # accepted only when E5 reads the words as what the rules found
                if match.intent not in INTENT_FIELDS or not set(INTENT_FIELDS[match.intent]) <= set(fields):
                    raise self.not_understood(parse.residual)
            elif match.intent is None or match.intent not in INTENT_FIELDS:
                raise self.not_understood(words)
            else:
                fields.update(INTENT_FIELDS[match.intent])
        if "follow" in parse.refs:
            fields["follow"] = self._reference(parse.refs["follow"], subject, ego_as_none=False)
        if "stop_behind" in parse.refs:
            stop = dict(fields.get("stop", {}))
            stop["behind"] = self._reference(parse.refs["stop_behind"], subject, ego_as_none=False)
            fields["stop"] = stop
        self._check_category(subject, fields)
        return fields

    def _check_category(self, subject: Subject, fields: dict[str, Any]) -> None:
        if not fields or subject.kind is None:
            return
        if subject.kind == "static":
            raise self.refuse(f"{subject.label!r} is a static object: it cannot move. Motion edits are for "
                              "vehicles (speed, stop, reverse, lane change, turn, delay, follow) and pedestrians "
                              "(cross the street, jaywalk, walk or run, stop, delay, speed)", "wrong_category")
        wrong = lex.VEHICLE_ONLY if subject.kind == "pedestrian" else lex.PEDESTRIAN_ONLY
        bad = [name for name in wrong if fields.get(name) not in (None, False)]
        if bad:
            can = ("cross the street, jaywalk, walk or run, stop, wait and change speed" if subject.kind == "pedestrian"
                   else "change speed, stop, reverse, change lanes, turn, wait and follow")
            what = " or ".join(lex.FIELD_WORDS[name] for name in bad)
            raise self.refuse(f"{subject.label!r} is a {subject.kind}, and {what} is not something a "
                              f"{subject.kind} does; a {subject.kind} can {can}", "wrong_category")

    def _modify(self, subjects: list[Subject], predicate: Sequence[str], placement: PlacementParse | None = None,
                continuation: bool = False) -> None:
        subjects = self.pending + subjects
        self.pending = []
        words = " ".join(predicate)
        for subject in subjects:
            self.subject = subject
            parse = parse_predicate(words, subject.kind) if predicate else PredicateParse()
            if parse.op == "remove":
                self._remove_subject(subject)
                continue
            fields = self._fields(parse, subject, words) if predicate else {}
            place = self._placement(placement, subject) if placement is not None else None
            if not fields and place is None:
                if parse.neutral and continuation:
                    continue
                raise self.refuse(f"{self.clause_text!r} does not say how {subject.label!r} should change")
            self._merge(subject, fields, place)

    def _merge(self, subject: Subject, fields: dict[str, Any], place: Placement | None = None) -> None:
        self._check_category(subject, fields)
        self.subject = subject
        if subject.inserted is not None:
            draft = self.drafts[subject.inserted]
            if set(fields) & set(draft.fields) or (place is not None and draft.placement is not None):
                raise self.refuse(f"{self.clause_text!r} asks {subject.label!r} for something it was already given")
            draft.fields.update(fields)
            draft.placement = place or draft.placement
            return
        last = self.drafts[-1] if self.drafts else None
        if (last is not None and last.op == "modify" and last.subject is not None and last.subject.ref == subject.ref
                and not set(fields) & set(last.fields) and not (place is not None and last.placement is not None)):
            last.fields.update(fields)
            last.placement = place or last.placement
            last.note = f"{last.note}; {self.clause_text}"[:500]
            return
        self._add(Draft("modify", self.clause_text, subject, placement=place, fields=fields))

    def _add(self, draft: Draft) -> None:
        self.drafts.append(draft)
        self.subject = draft.subject
