"""A predicate being read by rules: what was found so far, and the words not yet used.

``PredicateWork.take(regex, fn)`` applies ``fn`` to a match and blanks its words, so a later rule cannot
use them again ("stop behind the bus" is a stop, not also a placement); ``PredicateParse`` is the result.
The rules themselves are each behaviour's ``parse_rule`` (``editing.behaviours``; the speed, stop and timing ones
in ``editing.parse.speed``), run by ``editing.parse.behaviour``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from simsplat_core.editing.parse import chunks
from simsplat_core.scenario import vocabulary as voc

#: Words a predicate may hold that say nothing on their own.
IGNORABLE = frozenset(
    "the a an its their his her it them they to at in on of and then also just now right away instead again bit "
    "little lot much very really next first upcoming coming nearest lane road street there "
    "here be get is are will should must can could would may might shall as same time possible way that which who "
    "so soon please up down its own current please some more for with when while immediately straight ahead "
    "forward moving driving walking going travelling traveling running motion too well rather quite please "
    "completely entirely fully safely smoothly gradually gently normally please scene sequence clip log video "
    "from by through until till this these those one ones okay ok mode ego us me our my you your fast slow "
    "car vehicle pedestrian person please side curb kerb roadside having had has have do does did".split()
) | frozenset(voc.INTERSECTION_NOUNS)


@dataclass
class PredicateParse:
    """What a predicate asked for.

    Attributes:
        fields: ``Behaviour`` field values (``stop``: dict of ``StopSpec`` fields, ``behind`` left out).
        refs: noun phrases the behaviour points at: ``"follow"`` (the leader), ``"stop_behind"``.
        op: ``"remove"`` when the predicate means removal ("disappear").
        refusal: why the predicate cannot be done even though it was understood ("U-turns ...").
        refusal_field: the ``Behaviour`` field the refused request is about (for the category check).
        residual: words no rule used (filler removed); ``""`` when everything was understood.
        neutral: the predicate only says "go on" ("drive", "continue").
    """

    fields: dict[str, Any] = field(default_factory=dict)
    refs: dict[str, str] = field(default_factory=dict)
    op: str | None = None
    refusal: str | None = None
    refusal_field: str | None = None
    residual: str = ""
    neutral: bool = False

    @property
    def understood(self) -> bool:
        return bool(self.fields or self.refs or self.op or self.refusal or self.neutral)


class PredicateWork:
    """A predicate being read: the text with used words blanked, and what was found."""

    def __init__(self, text: str, kind: str | None) -> None:
        self.text = f" {text} "
        self.kind = kind
        self.out = PredicateParse()

    def take(self, rx: str, fn: Callable[[re.Match[str]], Any] | None = None, repeat: bool = False) -> bool:
        """Apply ``fn`` to the first (or every) match of ``rx`` and blank it; whether anything matched."""
        found = False
        for m in list(re.finditer(r"(?<![\w/-])(?:" + rx + r")(?![\w/-])", self.text)):
            if "|" in m.group(0):  # overlaps a phrase already used
                continue
            if fn is not None and fn(m) is False:
                continue
            self.blank(m.start(), m.end())
            found = True
            if not repeat:
                break
        return found

    def blank(self, start: int, end: int) -> None:
        self.text = self.text[:start] + " " + "|" * max(end - start - 2, 1) + " " + self.text[end:]

    def noun_phrase_after(self, end: int, exclude: tuple[str, ...] = ()) -> tuple[str, int]:
        """The noun phrase starting after character ``end`` (text, its end character); ``("", end)``: none."""
        phrase, _, stop = chunks.np_after(self.text, end, ("at", "after", "before", "until", "for", "with", "in",
                                                           "by", *exclude))
        return (phrase, stop) if phrase else ("", end)

    def set(self, name: str, value: Any) -> None:
        self.out.fields[name] = value

    def stop(self, **values: Any) -> None:
        self.out.fields.setdefault("stop", {}).update(values)
