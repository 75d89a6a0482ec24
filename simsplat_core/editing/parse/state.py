"""The state of a prompt being parsed: subjects, references, placements, behaviour fields, merging, refusals.

``editing.parse.clauses.PromptParser`` reads each clause's form; this base class turns what a clause names into
commands under construction (:class:`Draft`):

* subjects -- a noun phrase becomes a :class:`TargetRef` (ids read; the ego and non-objects such as "the
  sky" refused; plurals / "all" / "every" are groups) with the object's kind from the grounding parser;
  "it" / "them" are the previous subject, which may be an object this prompt inserts;
* references -- anchors, leaders and "stop behind X": the ego words are the ego, a pronoun is the last
  object named other than the subject;
* behaviour fields -- ``editing.parse.behaviour.parse_predicate``; words its rules leave over are given to E5
  (``editing.parse.semantic``) and accepted only when E5 reads them as a supported intent (the one the rules
  found, when they found one); then checked against the subject's kind ("wrong_category");
* merging -- consecutive predicates on one subject become one command when their fields do not clash.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from simsplat_core.editing.behaviours.registry import FIELD_WORDS, INTENT_FIELDS, PEDESTRIAN_ONLY, VEHICLE_ONLY
from simsplat_core.editing.commands import EGO, AssetSpec, Placement, TargetRef
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.editing.parse.anchor import agent_kind
from simsplat_core.editing.parse.behaviour import parse_predicate
from simsplat_core.editing.parse.placement import PlacementParse
from simsplat_core.editing.parse.predicate import PredicateParse
from simsplat_core.editing.parse.semantic import nearest_intent
from simsplat_core.editing.parse.text import number_word
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.grounding.parse import COLOR_SYNONYMS, NOUNS, parse_query
from simsplat_core.language.text import TextEncoder, default_text_encoder

INDEFINITE = ("a", "an", "another", "some", "one more")


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


def _conflicts(fields: dict[str, Any], given: dict[str, Any]) -> bool:
    """Whether ``fields`` change a value ``given`` already has ("pull up and stop" asks for one stop twice)."""
    return any(name in given and given[name] != value for name, value in fields.items())


def _is_ego(phrase: str) -> bool:
    return phrase in lex.EGO_WORDS


class PromptState:
    """Subjects, mentions and drafts of one prompt (module docstring)."""

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

    def refuse(self, what: str, reason: str = "unsupported") -> EditRefused:
        text = what if what.endswith(".") else what + "."
        if reason == "unsupported":
            text += " " + lex.SUPPORTED
        return EditRefused(text, reason=reason)

    def not_understood(self, words: str) -> EditRefused:
        where = f" in {self.clause_text!r}" if words != self.clause_text else ""
        return self.refuse(f"I could not understand {words!r}{where}")

    def finish(self) -> list[Draft]:
        if self.pending:
            raise self.refuse(f"I could not tell what should happen to {self.pending[0].label!r}")
        if not self.drafts:
            raise self.refuse(f"I found no edit in {self.prompt!r}")
        return self.drafts

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
        if t in INDEFINITE or chunks.match(tokens, i, lex.QUANTITY_PHRASES):
            return True
        if number_word(t) is not None and not chunks.is_quantity(tokens, i):
            return True
        j = i + 1 if t in COLOR_SYNONYMS else i
        k = chunks.head_noun(tokens, j)
        return k > 0 and (" ".join(tokens[j : j + k]) in NOUNS or " ".join(tokens[j : j + k]) in lex.EXTRA_ASSET_NOUNS)

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
            subject = Subject(TargetRef(description=phrase, group=group), agent_kind(query.categories), phrase)
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
        wrong = VEHICLE_ONLY if subject.kind == "pedestrian" else PEDESTRIAN_ONLY
        bad = [name for name in wrong if fields.get(name) not in (None, False)]
        if bad:
            can = ("cross the street, jaywalk, walk or run, stop, wait and change speed" if subject.kind == "pedestrian"
                   else "change speed, stop, reverse, change lanes, turn, wait and follow")
            what = " or ".join(FIELD_WORDS[name] for name in bad)
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
            if _conflicts(fields, draft.fields) or (place is not None and draft.placement is not None):
                raise self.refuse(f"{self.clause_text!r} asks {subject.label!r} for something it was already given")
            draft.fields.update(fields)
            draft.placement = place or draft.placement
            return
        last = self.drafts[-1] if self.drafts else None
        if (last is not None and last.op == "modify" and last.subject is not None and last.subject.ref == subject.ref
                and not _conflicts(fields, last.fields) and not (place is not None and last.placement is not None)):
            last.fields.update(fields)
            last.placement = place or last.placement
            last.note = f"{last.note}; {self.clause_text}"[:500]
            return
        self._add(Draft("modify", self.clause_text, subject, placement=place, fields=fields))

    def _add(self, draft: Draft) -> None:
        self.drafts.append(draft)
        self.subject = draft.subject
