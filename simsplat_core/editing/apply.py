"""Apply an edit program to a scene, by value: ground, place, plan, build the edited graph, validate.

    ctx = EditContext.create(log, graph, language_scene, engine, bank)
    edited = apply_edit(ctx, program)                 # EditedScene; raises EditRefused
    edited = Editor(ctx).edit("remove the white van and make the red car stop")
    edited.graph, edited.states, edited.delta, edited.validation

Commands run in order on a working copy (:class:`~simsplat_core.editing.draft.Draft`): each grounds its
target / anchor against the scene's language (``editing.grounding``), then

* ``remove`` drops the nodes and their agents (every match of a group target);
* ``replace`` keeps each target's trajectory and swaps its appearance for a bank asset: a new node on the
  same track, the asset's own box size, the box kept on the ground (same object id, source ``edited``);
* ``insert`` retrieves an asset, resolves the placement on the lane graph / sidewalk (``editing.placement.resolve``)
  and plans its motion (``editing.motion.controller``; vehicles drive along their lane, static objects and
  rows of cones stand still, pedestrians walk along the sidewalk or cross when told);
* ``modify`` re-plans a target's trajectory from its log trajectory (``editing.motion.controller``).

An added object whose command asked a colour is then looked at in the edited renders and
exposure-matched when it reads as another shade (``editing.assets.look_check``); when no gain makes it read as asked,
the program is applied again without that asset (at most ``LOOK_RETRIES`` times; the attempt with the most
objects reading as asked is kept). The edited graph is
:func:`~simsplat_core.editing.delta.apply_delta` of the stored graph and the resulting delta (the same
function rebuilds a stored edit), so nothing of the stored scene changes and
unchanged nodes are shared. Finally every edited and inserted agent is validated against every other
agent (``scenario.metrics.validate_agents``). A command whose grounding fails, whose placement or motion
is infeasible, or that changes nothing is refused (``EditRefused``, with the command's index).

After the commands, the traffic reacts (``motion.refine``, ``EditorOptions.refinement``; default ``"full"``):
every other agent is rolled out by the motion predictor (default ``motion.reactive.ReactivePredictor``) around
the edited agents' fixed trajectories, reacting agents get ``source == "refined"`` and new pose tracks in
the delta, and they are validated with the edited ones. ``"none"`` keeps the log for everyone else. When the
reacting traffic cannot take an inserted object where asked without a crash, the program is applied again with
the inserted objects a little further along their lanes, within the placement's slack (``editing.traffic.room``).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable

from simsplat_core.editing.assets.bank import asked_top_color
from simsplat_core.editing.assets.look_check import match_exposure
from simsplat_core.editing.assets.record import VARIANT_SEP, Asset
from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.draft import Draft, EditContext
from simsplat_core.editing.grounding import Grounder
from simsplat_core.editing.ops import apply_command, node_factory
from simsplat_core.editing.options import CHATSIM_LIKE, DEFAULT_OPTIONS, OMNIRE_LIKE, EditorOptions
from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.editing.result import CommandOutcome, EditDelta, EditedScene, EditRefused
from simsplat_core.editing.traffic.reaction import react
from simsplat_core.editing.traffic.room import ROOM_SHIFTS, changed_rows, searches_room, traffic_copes
from simsplat_core.scenario.metrics import validate_agents
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.stage_clock import StageClock, maybe_stage

logger = logging.getLogger(__name__)

__all__ = ["CHATSIM_LIKE", "OMNIRE_LIKE", "Editor", "EditorOptions", "apply_edit"]


def apply_edit(ctx: EditContext, program: EditProgram, options: EditorOptions = DEFAULT_OPTIONS) -> EditedScene:
    """Apply ``program`` to ``ctx.graph`` (module docstring).

    Raises:
        EditRefused: a command cannot be carried out (its ``command_index`` says which), or the program as a
            whole changes nothing.
    """
    clock = StageClock()
    excluded: frozenset[str] = frozenset()
    best: tuple[int, Draft, SceneGraph, EditDelta, list[CommandOutcome]] | None = None
    for attempt in range(LOOK_RETRIES + 1):
        draft, outcomes, delta = _run_with_room(ctx, program, options, excluded, clock)
        if not options.check_looks:
            with clock.stage("apply"):
                best = (0, draft, _build_graph(ctx, draft, delta), delta, outcomes)
            break
        with clock.stage("apply"):
            graph, delta, outcomes, misfits, fitted = _looked(ctx, draft, outcomes, delta)
        if best is None or fitted > best[0]:
            best = (fitted, draft, graph, delta, outcomes)
        if not misfits:
            break
        if attempt == LOOK_RETRIES:
            logger.warning("%s: no asset tried reads as the asked colour everywhere; keeping the closest "
                           "(the outcome's summary says how it reads)", ctx.log.seq_id)
            break
        logger.info("%s: %s do(es) not read as asked here; trying other assets", ctx.log.seq_id, sorted(misfits))
        excluded |= misfits
    assert best is not None  # the loop runs at least once
    _, draft, graph, delta, outcomes = best
    with clock.stage("validate"):
        validation = validate_agents(draft.states, ctx.map_ctx, changed_rows(draft.states))
    logger.info("%s: %d command(s): %s; validation %s", ctx.log.seq_id, len(outcomes),
                "; ".join(o.summary for o in outcomes), "ok" if validation.ok else validation.failures())
    return EditedScene(prompt=program.prompt, original=ctx.graph, graph=graph, original_states=ctx.states,
                       states=draft.states, delta=delta, outcomes=tuple(outcomes), validation=validation,
                       refinement=draft.refinement, seconds=dict(clock.seconds))


#: Times a program is re-applied with other assets when an inserted object does not read as the asked colour.
LOOK_RETRIES = 1


def _run_with_room(ctx: EditContext, program: EditProgram, options: EditorOptions, excluded: frozenset[str],
                   clock: StageClock | None = None) -> tuple[Draft, list[CommandOutcome], EditDelta]:
    """:func:`_run_commands` with the inserted objects where asked; when the reacting traffic cannot cope there,
    the first of ``room.ROOM_SHIFTS`` where it can (else the asked spot)."""
    asked = _run_commands(ctx, program, options, excluded, clock=clock)
    if not searches_room(program, options.refinement) or traffic_copes(asked[0]):
        return asked
    for share in ROOM_SHIFTS:
        try:
            moved = _run_commands(ctx, program, options, excluded, room_shift=share, clock=clock)
        except EditRefused:  # no room there (or the program fails there): the next spot
            continue
        if traffic_copes(moved[0]):
            logger.info("%s: inserted objects moved by %+.1f of their placement slack for the traffic", ctx.log.seq_id,
                        share)
            return moved
    return asked


def _run_commands(ctx: EditContext, program: EditProgram, options: EditorOptions, excluded: frozenset[str],
                  room_shift: float = 0.0, clock: StageClock | None = None
                  ) -> tuple[Draft, list[CommandOutcome], EditDelta]:
    """Every command on a fresh draft (assets in ``excluded`` are not retrieved when another fits; inserted rows
    moved by ``room_shift``, ``Draft.room_shift``); seconds into ``clock`` (``ground`` / ``apply`` / ``refine``)."""
    with maybe_stage(clock, "apply"):
        grounder = Grounder(ctx.language, ctx.engine, ctx.graph, options.grounding, clock=clock, states=ctx.states,
                            lanes=ctx.lanes)
        draft = Draft.start(ctx, grounder, options, excluded, room_shift)
        outcomes = []
        for index, command in enumerate(program.commands):
            options.check(command, index)
            outcomes.append(apply_command(draft, command, index))
        if draft.delta().is_empty:
            raise EditRefused("the edit changes nothing in this scene", reason="unsupported")
    if options.refinement != "none":
        with maybe_stage(clock, "refine"):
            react(draft, options.refinement, options.ego_reacts)
    return draft, outcomes, draft.delta()


def _looked(ctx: EditContext, draft: Draft, outcomes: list[CommandOutcome], delta: EditDelta
            ) -> tuple[SceneGraph, EditDelta, list[CommandOutcome], frozenset[str], int]:
    """The edited graph after the look check (``editing.assets.look_check``): exposure-matched delta and graph, outcomes
    noting the gains, the stored asset ids of added objects that do not read as asked (after their gain), and
    how many do."""
    asset_of = _asset_source(ctx, draft)

    def build(changed: EditDelta) -> SceneGraph:
        return _build_graph(ctx, draft, changed)

    stored_asset = {a.node_id: a.asset_id.split(VARIANT_SEP, 1)[0] for a in delta.added}
    matched, graph, notes = match_exposure(ctx.log, build(delta), delta, _asked_colors(outcomes, delta),
                                           draft.states, asset_of, build)
    misfits = frozenset(stored_asset[n.node_id] for n in notes if n.seen is not None and not n.fitted)
    outcomes = [_with_look_notes(o, [n.describe() for n in notes if n.gain != 1.0 and n.node_id in nodes])
                for o, nodes in zip(outcomes, _added_nodes(outcomes, matched))]
    return graph, matched, outcomes, misfits, sum(n.fitted for n in notes)


def _asset_source(ctx: EditContext, draft: Draft) -> Callable[[str], Asset]:
    """Assets by id (variants included): those the draft retrieved, others from the bank."""
    def asset_of(asset_id: str) -> Asset:
        if asset_id not in draft.assets and ctx.bank is not None:
            draft.assets[asset_id] = ctx.bank.get(asset_id)
        return draft.assets[asset_id]

    return asset_of


def _build_graph(ctx: EditContext, draft: Draft, delta: EditDelta) -> SceneGraph:
    """The stored graph with ``delta`` applied."""
    return apply_delta(ctx.graph, delta, node_factory(_asset_source(ctx, draft), ctx.graph.frame_indices))


def _added_nodes(outcomes: list[CommandOutcome], delta: EditDelta) -> list[set[int]]:
    """Per outcome, the added node ids of the objects it inserted or replaced."""
    out = []
    for outcome in outcomes:
        objects = set(outcome.new_object_ids) | set(outcome.changed_object_ids)
        out.append({a.node_id for a in delta.added if a.object_id in objects} if outcome.command.asset else set())
    return out


def _asked_colors(outcomes: list[CommandOutcome], delta: EditDelta) -> dict[int, str]:
    """Added node id -> the colour its command asked for (nodes of commands that asked none are left out)."""
    asked = {}
    for outcome, nodes in zip(outcomes, _added_nodes(outcomes, delta)):
        spec = outcome.command.asset
        color = asked_top_color(spec) if spec is not None else None  # a pedestrian's top: its main colour
        if color is not None:
            asked.update(dict.fromkeys(nodes, color))
    return asked


def _with_look_notes(outcome: CommandOutcome, notes: list[str]) -> CommandOutcome:
    return dataclasses.replace(outcome, summary=f"{outcome.summary}; {'; '.join(notes)}") if notes else outcome


class Editor:
    """Parse and apply prompts in one scene: ``Editor(ctx, options).edit("insert a yellow taxi ahead")``."""

    def __init__(self, ctx: EditContext, options: EditorOptions = DEFAULT_OPTIONS) -> None:
        self.ctx = ctx
        self.options = options

    def parse(self, prompt: str) -> EditProgram:
        """The program of ``prompt`` (``parse_prompt`` with the engine's text encoder).

        Raises:
            EditRefused: the words ask for something the command language cannot express.
        """
        program = parse_prompt(prompt, encoder=self.ctx.engine.text_encoder)
        return program if program.prompt else program.model_copy(update={"prompt": prompt})

    def edit(self, prompt: str) -> EditedScene:
        """Parse ``prompt`` and apply it. Raises ``EditRefused``."""
        return apply_edit(self.ctx, self.parse(prompt), self.options)
