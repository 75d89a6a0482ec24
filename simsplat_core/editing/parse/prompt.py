"""The offline English -> :class:`EditProgram` parser.

    parse_prompt("remove the white van and make the red car stop before the crosswalk")
    # EditProgram(commands=[EditCommand(op="remove", target=TargetRef(description="the white van")),
    #                       EditCommand(op="modify", target=TargetRef(description="the red car"),
    #                                   behaviour=Behaviour(stop=StopSpec(before="crosswalk")))])

How (one module per step):

1. ``editing.parse.text`` -- case, contractions, "pls", number words before units, units ("20kph" -> "20 km/h"),
   coordinates ("(10, -3, 0)", "x=12 y=3");
2. ``editing.parse.chunks`` -- clauses ("... and make the red car stop" starts a new one; "between the bus and the
   truck" does not) and noun phrases, on the grounding lexicon's nouns and colours;
3. ``editing.parse.clauses`` -- each clause's form (replace / remove / insert / "make X ..." / "stop X ..." / "X
   should ..." / a bare predicate on the previous subject); ``editing.parse.state`` -- subjects, pronouns,
   references, category checks, merging;
4. ``editing.parse.placement`` (placements, assets; ``editing.parse.anchor`` tells the anchor's describing phrases
   from the inserted object's own verb phrases), ``editing.parse.speed`` and ``editing.parse.behaviour`` (behaviours, on
   ``editing.parse.predicate``) by rule; a predicate no rule knows is matched to the scenario vocabulary through
   the grounding lexicon's motion keywords, then by E5 (``editing.parse.semantic``) to the nearest supported
   intent, or refused. The edit language's own words are in ``editing.parse.lexicon``.

Target and anchor descriptions keep the whole noun phrase ("the white van on the left", "the pedestrian
crossing the street") for the grounding engine; plurals and "all" / "every" set ``group``. Whether the
scene has such an object, room for a placement or an intersection ahead is for ``apply_edit``; what the
words cannot express is refused here with :class:`EditRefused` ("unsupported", or "wrong_category" for a
pedestrian changing lanes or a cone turning), its message naming what was not understood and what is
supported. A prompt is never parsed into nothing: no edit found is a refusal too.
"""

from __future__ import annotations

import logging
import re
from typing import Any

from pydantic import ValidationError

from simsplat_core.editing.commands import Behaviour, EditCommand, EditProgram, SpeedSpec, StopSpec
from simsplat_core.editing.parse.chunks import split_clauses
from simsplat_core.editing.parse.clauses import PromptParser
from simsplat_core.editing.parse.lexicon import SUPPORTED
from simsplat_core.editing.parse.state import Draft
from simsplat_core.editing.parse.text import canonical
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.text import TextEncoder

logger = logging.getLogger(__name__)

__all__ = ["SUPPORTED", "parse_prompt"]


def parse_prompt(text: str, *, encoder: TextEncoder | None = None) -> EditProgram:
    """Parse a free-form edit request into an :class:`EditProgram` (module docstring).

    Args:
        text: the prompt as typed.
        encoder: text encoder for words the rules do not know (E5 protocol); default
            ``language.text.default_text_encoder()``, loaded only when such words occur.

    Raises:
        EditRefused: ``reason`` "unsupported" (nothing recognisable, or something the command language
            cannot express), "wrong_category" (a behaviour the object's kind cannot have) or
            "invalid_command" (a value out of the schema's range, e.g. 500 km/h).
    """
    if not isinstance(text, str) or not text.strip():
        raise EditRefused("The prompt is empty: say what to edit. " + SUPPORTED, reason="unsupported")
    canon = canonical(text)
    parser = PromptParser(text, canon.positions, encoder)
    for clause in split_clauses(canon.tokens):
        parser.clause(clause)
    drafts = parser.finish()
    commands = [_command(d, i) for i, d in enumerate(drafts)]
    logger.debug("parsed %r into %d command(s)", text, len(commands))
    return EditProgram(prompt=text, commands=commands)


#: An inserted object described by one of these words stands still (an absolute speed of 0, which parks an
#: inserted vehicle) when no behaviour is asked ("insert a stopped truck in the ego lane").
STANDING_WORDS = re.compile(r"(?<![\w-])(?:stopped|stationary|halted|standing|parked)(?![\w-])")


def _inserted_standing(draft: Draft) -> bool:
    return draft.op == "insert" and not draft.fields and draft.asset is not None \
        and STANDING_WORDS.search(draft.asset.description.lower()) is not None


def _behaviour(fields: dict[str, Any]) -> Behaviour | None:
    if not fields:
        return None
    values = dict(fields)
    if "stop" in values:
        values["stop"] = StopSpec(**values["stop"])
    return Behaviour(**values)


def _command(draft: Draft, index: int) -> EditCommand:
    try:
        return EditCommand(
            op=draft.op,  # type: ignore[arg-type]
            target=draft.subject.ref if draft.op != "insert" and draft.subject is not None else None,
            asset=draft.asset,
            placement=draft.placement,
            behaviour=Behaviour(speed=SpeedSpec(value=0.0)) if _inserted_standing(draft) else _behaviour(draft.fields),
            note=draft.note[:500],
        )
    except ValidationError as exc:
        error = exc.errors()[0]
        where = ".".join(str(p) for p in error["loc"]) or "command"
        raise EditRefused(f"{draft.note!r} gives an invalid {draft.op} command ({where}: {error['msg']})",
                          reason="invalid_command", command_index=index) from exc
