"""``BehaviourDecl``: one motion behaviour of the edit language, declared once.

A behaviour is what ``commands.Behaviour`` lets a command ask of an agent (stop, reverse, change lanes, ...).
Its declaration holds everything the edit language knows of it: the ``Behaviour`` fields it sets, which agents may
do it, its *intents* (what an unknown verb may be mapped to, with the fields each sets and its imperative
phrasings for E5), the scenario-vocabulary motion classes that mean it, the sentence forms that ask for it in the
mining rule client's proposals and in the editing benchmark's prompts, the parser rule that reads its words
(``parse_rule``) and, for a manoeuvre, how the trajectory auto-labeller's motion class shows it (``label_check``,
which the editing benchmark's and the mining judge's checks both apply). The registry
(``editing.behaviours.registry``) collects the declarations and derives the tables the parser, the motion
requests, the checks, the benchmark's prompt generator and the rule client read. The planner (the motion
controller's route / speed plan, ``editing.motion``) and the layer-specific parts of the checks
(``eval.editing.checks.MOTION_CHECKS``, ``mining.rule_judge.CHANGE_CHECKS``) are code keyed by the field and
behaviour names declared here (``docs/extending_behaviours.md``). A behaviour that sets a speed declares its rule
(``speed_rule``); ``registry.SPEED_ORDER`` is their precedence.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse.predicate import PredicateWork

#: The agents a behaviour may be restricted to.
AgentKind = Literal["vehicle", "pedestrian"]
#: A parser rule: reads the behaviour's words off a canonical predicate (``PredicateWork.take``, which blanks
#: the words it used) and sets its ``Behaviour`` fields (``PredicateWork.set``).
ParseRule = Callable[[PredicateWork], None]
#: A speed rule: ``(behaviour, the agent's current |speed| m/s, the agent's kind) ->`` the speed the behaviour asks
#: of it, m/s, or ``None`` when it asks none (its fields are unset, or it leaves the speed to a rule after it in
#: ``registry.SPEED_ORDER``). Only rules of behaviours the agent's kind may do are asked.
SpeedRule = Callable[[Behaviour, float, AgentKind], float | None]


@dataclass(frozen=True)
class Intent:
    """One thing a prompt may ask (an intent of the parser's E5 fallback, ``editing.parse.semantic``).

    Attributes:
        name: the intent's name (``"lane_left"``).
        fields: the ``Behaviour`` field values it sets (``{"lane_change": "left"}``; ``stop`` is a dict of
            ``StopSpec`` fields), or ``None`` when it needs more than fixed values (``follow`` needs a leader).
        phrases: imperative phrasings of it (E5 passages), in the order they are embedded.
        family: intents of one family are close enough that E5 need not tell them apart (``"slowing"``: stop,
            brake hard, slow down); ``None``: its own.
    """

    name: str
    fields: dict[str, Any] | None = None
    phrases: tuple[str, ...] = ()
    family: str | None = None


@dataclass(frozen=True)
class LabelCheck:
    """How an agent asked the behaviour shows in the trajectory auto-labeller's motion class of its edited
    trajectory (``language.motion_labels``): what the editing benchmark's check (``eval.editing.checks``) and the
    mining judge's (``mining.rule_judge``) both require of a manoeuvre.

    Attributes:
        field: the ``Behaviour`` field whose asked value is checked (``eval.editing.intents.MotionIntent`` names it
            alike); a false value (``None``, ``False``) asks nothing.
        shows: ``(asked value, motion class) ->`` whether the class shows the asked value.
        missing: ``asked value ->`` what a class that does not show it lacks, in words (``"not reversing"``,
            ``"asked changing_lane_left"``); the checks prefix ``"labelled <class>, "``.
    """

    field: str
    shows: Callable[[Any, str], bool]
    missing: Callable[[Any], str]


@dataclass(frozen=True)
class BehaviourDecl:
    """A motion behaviour of the edit language (module docstring).

    Attributes:
        name: the behaviour's name (``"lane_change"``).
        fields: the ``commands.Behaviour`` fields it sets.
        agent: the only kind of agent that may do it (``None``: vehicles and pedestrians).
        words: the behaviour in words, for refusals naming the wrong kind of agent (agent-restricted ones).
        intents: the intents that ask for it, in the order their phrasings are embedded.
        motion_classes: scenario-vocabulary motion class -> the intent of asking an agent to do it.
        proposal_forms: mining rule client proposal kind -> its sentence forms (``mining.rule_wording``).
        prompt_forms: editing benchmark intent kind -> its sentence forms (``eval.editing.wording``).
        parse_rule: the parser's rule for its words (``None``: another behaviour's rule reads them, as the
            street-crossing rule reads "jaywalk"); ``registry.PARSE_ORDER`` runs the rules in a fixed order.
        label_check: how the auto-labeller's motion class shows it (manoeuvres: reversing, lane changes, turns,
            crossing); ``None``: the checks measure it otherwise (speeds, stops, timing) or not at all.
        speed_rule: the speed it asks (``editing.motion.requests.target_speed`` asks the rules in
            ``registry.SPEED_ORDER``; the first speed given wins); ``None``: it keeps the speed (turns, stops).
    """

    name: str
    fields: tuple[str, ...]
    agent: AgentKind | None = None
    words: str = ""
    intents: tuple[Intent, ...] = ()
    motion_classes: Mapping[str, str] = field(default_factory=dict)
    proposal_forms: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    prompt_forms: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    parse_rule: ParseRule | None = None
    label_check: LabelCheck | None = None
    speed_rule: SpeedRule | None = None

    def __post_init__(self) -> None:
        names = {i.name for i in self.intents}
        unknown = sorted(set(self.motion_classes.values()) - names)
        if unknown:
            raise ValueError(f"behaviour {self.name!r}: motion_classes name unknown intents {unknown}")
        if self.agent is not None and not self.words:
            raise ValueError(f"behaviour {self.name!r}: an agent-restricted behaviour needs its words")
        if self.label_check is not None and self.label_check.field not in self.fields:
            raise ValueError(f"behaviour {self.name!r}: its label check reads {self.label_check.field!r}, not one of "
                             f"its fields {list(self.fields)}")
        for intent in self.intents:
            if intent.fields is not None and not set(intent.fields) & set(self.fields):
                raise ValueError(f"behaviour {self.name!r}: intent {intent.name!r} sets none of its fields")
