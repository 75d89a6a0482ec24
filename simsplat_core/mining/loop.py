"""The mining loop of one sequence: propose -> command -> edit (ground, apply, refine, validate) -> render -> judge
-> accept, or adjust and retry.

    result = mine_sequence(ctx, RuleBasedVLMClient(seed=0), MiningConfig(scenarios=3))
    for record in result.accepted:              # AttemptRecord, .export is True, .edited holds the EditedScene
        ...
    rows = attempt_rows(result, run_id)         # the edits table's rows (mining.attempts)

Per proposal (``mining.proposal_feed``: seed prompts first -- e.g. search hits -- then the client's, in rounds,
without repeats), until ``config.scenarios`` are accepted or the proposals run out:

1. ``client.to_command`` -- a refusal (``EditRefused``, e.g. the rule-based client's ``ProposalRejected``, or a
   program failing the schema) is a ``"refused"`` attempt, a failed call (``VLMError``, a malformed answer) a
   ``"failed"`` one; both count as an attempt and the loop moves on to the next proposal;
2. up to ``config.max_attempts`` attempts of the program: ``editing.apply.apply_edit`` with ``config.options``
   (on the stored scene by value: ``ctx`` is never changed; a refusal is a ``"refused"`` attempt); the judge's
   views (``mining.judge_views``: a few telling frames, small, with the targets' pixels, and the BEV); the
   :class:`~simsplat_core.mining.vlm_protocol.JudgeRequest` (``judge_input.judge_request_from_edit``);
   ``client.judge`` (a failed call: a ``"failed"`` attempt, the proposal is dropped). The attempt is
   ``"accepted"`` when the edit's validation passes -- a collision or an off-road agent is never accepted, whatever
   the judge says -- and the judge says it follows the prompt with plausibility at least
   ``config.min_plausibility``; else ``"rejected"``, and the next attempt runs the program adjusted by the judge's
   parameter changes, or by a default change for the failure class (``mining.adjust``: collision, off-road, the
   targets covering fewer than ``config.min_visible_pixels`` pixels, a refused placement). A refusal because the
   words of the target (or anchor) did not ground is retried naming the object the proposer meant by id
   (``Pending.target_id``, ``adjust.retarget``; proposers that do not say which object they meant are not
   retried). When nothing can be adjusted the loop moves on.

An endpoint that is down stops the sequence early: after :data:`MAX_UNREACHABLE_IN_A_ROW` attempts in a row whose
client call could not reach it (``VLMUnreachableError``, each already retried by the client), the remaining proposals
are not attempted (they get no row; the log says why), so a run with the VLM down spends a few bounded calls per
sequence, records each as ``"failed"`` with its reason, and goes on.

Decisions depend only on the scene, the client's answers and the config (timings are recorded, never read), so
the rule-based client gives the same records for the same seed. Every attempt is an
:class:`~simsplat_core.mining.attempts.AttemptRecord`.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pydantic

from simsplat_core.editing.apply import apply_edit
from simsplat_core.editing.assets.record import VARIANT_SEP
from simsplat_core.editing.commands import AssetSpec, EditProgram
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.options import DEFAULT_OPTIONS, EditorOptions
from simsplat_core.editing.result import EditedScene, EditRefused
from simsplat_core.mining.adjust import Adjustment, AlternativeAsset, adjust_program, retarget
from simsplat_core.mining.attempts import TIMED_STAGES, AttemptRecord, AttemptStatus, MiningResult, scenario_key
from simsplat_core.mining.edit_kinds import command_kinds, edit_category
from simsplat_core.mining.judge_input import judge_request_from_edit, targets_of, validation_failures
from simsplat_core.mining.judge_views import JudgeViews, judge_views, proposal_views
from simsplat_core.mining.proposal_feed import Pending, ProposalFeed
from simsplat_core.mining.rule_client import RuleBasedVLMClient
from simsplat_core.mining.rule_proposals import Proposal, selected_categories
from simsplat_core.mining.scene_facts import scene_facts, summary
from simsplat_core.mining.vlm_protocol import PLAUSIBILITY_MAX, PLAUSIBILITY_MIN, Judgement, SceneSummary, VLMClient
from simsplat_core.vlm.openai_chat import VLMError, VLMUnreachableError

logger = logging.getLogger(__name__)

#: ``progress(accepted, wanted)`` after each attempt.
MiningProgress = Callable[[int, int], None]
#: Attempts in a row that could not reach the VLM endpoint before a sequence stops (module docstring).
MAX_UNREACHABLE_IN_A_ROW = 3


@dataclass(frozen=True)
class MiningConfig:
    """How one sequence is mined.

    Attributes:
        scenarios: accepted scenarios wanted per sequence (K; the loop stops there).
        max_attempts: attempts per proposal (the first plus the adjusted retries).
        proposals_per_round: prompts asked of the client per round; max_rounds: most rounds per sequence.
        judge_frames: telling frames rendered for the judge (one camera each: where the targets show most).
        judge_width: width bound (pixels) of the judge's renders and of the proposal views.
        bev_size: side (pixels) of the judge's bird's-eye view.
        min_plausibility: least judged plausibility accepted (``1..4``).
        min_visible_pixels: targets covering fewer pixels of the judge's renders count as not visible (the default
            adjustment then brings them closer).
        seed: the run's seed: part of every ``edit_id`` (and the rule-based client's, :func:`default_client`).
        category_offset: where this sequence starts in the run's order of edit categories (the rule-based client's,
            :func:`default_client`; a run sets ``i * scenarios`` for its ``i``-th sequence so that its sequences
            take the categories in turn; ``None``: each sequence its own seeded order).
        categories: the edit categories wanted (``rule_proposals.EDIT_CATEGORIES``; empty: all). The rule-based
            client proposes only those; a proposal of any client whose category is known to be another one (said by
            its proposer, or the category of its command program) is refused as ``category_not_selected``.
        options: the editor's options (default: full refinement, the ego reacts).
    """

    scenarios: int = 3
    max_attempts: int = 3
    proposals_per_round: int = 6
    max_rounds: int = 3
    judge_frames: int = 3
    judge_width: int = 320
    bev_size: int = 320
    min_plausibility: int = 3
    min_visible_pixels: int = 30
    seed: int = 0
    category_offset: int | None = None
    categories: tuple[str, ...] = ()
    options: EditorOptions = field(default=DEFAULT_OPTIONS)

    def __post_init__(self) -> None:
        for name in ("scenarios", "max_attempts", "proposals_per_round", "max_rounds", "judge_frames", "judge_width",
                     "bev_size"):
            if getattr(self, name) < 1:
                raise ValueError(f"MiningConfig.{name} must be >= 1, got {getattr(self, name)}")
        if not PLAUSIBILITY_MIN <= self.min_plausibility <= PLAUSIBILITY_MAX:
            raise ValueError(f"MiningConfig.min_plausibility must be within {PLAUSIBILITY_MIN}..{PLAUSIBILITY_MAX}, "
                             f"got {self.min_plausibility}")
        if self.min_visible_pixels < 0:
            raise ValueError(f"MiningConfig.min_visible_pixels must be >= 0, got {self.min_visible_pixels}")
        try:
            selected_categories(self.categories)
        except ValueError as exc:
            raise ValueError(f"MiningConfig.categories: {exc}") from exc


def default_client(ctx: EditContext, config: MiningConfig) -> RuleBasedVLMClient:
    """The rule-based client of ``config.seed``, ``config.category_offset`` and ``config.categories``, parsing with
    the context's text encoder."""
    return RuleBasedVLMClient(config.seed, encoder=ctx.engine.text_encoder, category_offset=config.category_offset,
                              categories=config.categories)


def program_json(program: EditProgram | None) -> str:
    """The ``edits.command_json`` of ``program``: compact, keys sorted (``""`` for none)."""
    return "" if program is None else json.dumps(program.model_dump(mode="json"), sort_keys=True)


def _error(exc: Exception) -> str:
    return f"{type(exc).__name__}: {exc}"


def _refusal(exc: EditRefused) -> str:
    where = f"command {exc.command_index + 1}: " if exc.command_index is not None else ""
    return f"{exc.reason}: {where}{exc}"


def rejection_reason(edited: EditedScene, verdict: Judgement, min_plausibility: int) -> str:
    """``"rejected: validation: ... | judge: ..."``: the validation's failures and the judge's verdict and reasons."""
    parts = []
    if not edited.validation.ok:
        parts.append("validation: " + "; ".join(edited.validation.failures()))
    follows = "follows the prompt" if verdict.follows_prompt else "does not follow the prompt"
    parts.append(f"judge: {follows}, plausibility {verdict.plausibility}/{PLAUSIBILITY_MAX} (least "
                 f"{min_plausibility}): " + "; ".join(verdict.reasons))
    return "rejected: " + " | ".join(parts)


def failure_classes(edited: EditedScene, shown: JudgeViews, min_visible_pixels: int) -> set[str]:
    """The edit's failure classes for the default adjustments: the validation's kinds, and ``not_visible`` when
    every target present covers fewer than ``min_visible_pixels`` pixels of the judge's renders."""
    found: set[str] = {f.kind for f in validation_failures(edited.validation)}
    present = [o for ids in targets_of(edited) for o in ids if o in edited.states.object_ids]
    seen = shown.visible_pixels
    if seen is not None and present and all(seen.get(o, 0) < min_visible_pixels for o in present):
        found.add("not_visible")
    return found


def asset_alternatives(ctx: EditContext, used: set[str]) -> AlternativeAsset | None:
    """``pick(spec)``: the bank's best asset for ``spec`` among those not in ``used`` (stored asset ids), ``None``
    when no other fits (``AssetBank.retrieve`` with ``exclude``); ``None`` without a bank."""
    bank = ctx.bank
    if bank is None:
        return None

    def pick(spec: AssetSpec) -> str | None:
        try:
            asset = bank.retrieve(spec.model_copy(update={"asset_id": None}), ctx.engine.text_encoder,
                                  exclude=frozenset(used))
        except EditRefused:
            return None
        return None if asset.asset_id.split(VARIANT_SEP, 1)[0] in used else asset.asset_id

    return pick


@dataclass
class _Scenario:
    """One proposal being worked on (private to :class:`_Miner`)."""

    index: int
    pending: Pending
    edit_id: str
    used_assets: set[str] = field(default_factory=set)


class _Miner:
    """The per-proposal steps of :func:`mine_sequence` (module docstring)."""

    def __init__(self, ctx: EditContext, client: VLMClient, config: MiningConfig, scene: SceneSummary) -> None:
        self.ctx = ctx
        self.client = client
        self.config = config
        self.scene = scene
        #: Client calls in a row that could not reach the endpoint (reset by any answer).
        self.unreachable_in_a_row = 0

    def _answered(self) -> None:
        self.unreachable_in_a_row = 0

    def _failed_call(self, exc: Exception) -> None:
        self.unreachable_in_a_row = self.unreachable_in_a_row + 1 if isinstance(exc, VLMUnreachableError) else 0

    def _record(self, s: _Scenario, attempt: int, status: AttemptStatus, reason: str, seconds: dict[str, float], *,
                program: EditProgram | None = None, category: str = "", verdict: Judgement | None = None,
                adjustment: str = "", edited: EditedScene | None = None) -> AttemptRecord:
        record = AttemptRecord(
            seq_id=self.ctx.log.seq_id, scenario=s.index, attempt=attempt, edit_id=s.edit_id, prompt=s.pending.prompt,
            source=s.pending.source, category=s.pending.category or category, program_json=program_json(program),
            status=status, failure_reason=reason, follows_prompt=None if verdict is None else verdict.follows_prompt,
            plausibility=None if verdict is None else verdict.plausibility, judgement=verdict,
            adjustment=adjustment, seconds={stage: seconds.get(stage, 0.0) for stage in TIMED_STAGES}, edited=edited)
        logger.info("%s scenario %d attempt %d: %s %r%s", record.seq_id, s.index, attempt, status, s.pending.prompt,
                    f" ({reason})" if reason else "")
        return record

    def _selected(self, category: str) -> bool:
        """Whether ``category`` is among the config's edit categories (all when it names none)."""
        return not self.config.categories or category in self.config.categories

    def _not_selected(self, category: str) -> str:
        return f"category_not_selected: {category} is not among {list(self.config.categories)}"

    def proposing_failed(self, index: int, pending: Pending) -> AttemptRecord:
        s = _Scenario(index, pending, scenario_key(self.ctx.log.seq_id, self.config.seed, index, ""))
        return self._record(s, 1, "failed", f"vlm_error: propose: {pending.error}", {"propose": pending.propose_s})

    def scenario(self, index: int, pending: Pending, progress: Callable[[AttemptRecord], None]) -> None:
        """Every attempt of one proposal, each handed to ``progress`` as it is made."""
        s = _Scenario(index, pending, scenario_key(self.ctx.log.seq_id, self.config.seed, index, pending.prompt))
        seconds = {"propose": pending.propose_s}
        if pending.category and not self._selected(pending.category):
            progress(self._record(s, 1, "refused", self._not_selected(pending.category), seconds))
            return
        started = time.perf_counter()
        try:
            program = self.client.to_command(pending.prompt, self.scene)
        except EditRefused as exc:  # an answer: the endpoint was reached
            self._answered()
            seconds["command"] = time.perf_counter() - started
            progress(self._record(s, 1, "refused", _refusal(exc), seconds))
            return
        except pydantic.ValidationError as exc:
            self._answered()
            seconds["command"] = time.perf_counter() - started
            progress(self._record(s, 1, "refused", f"invalid_command: {_error(exc)}", seconds))
            return
        except (VLMError, ValueError) as exc:
            seconds["command"] = time.perf_counter() - started
            self._failed_call(exc)
            progress(self._record(s, 1, "failed", f"vlm_error: command: {_error(exc)}", seconds))
            return
        self._answered()
        seconds["command"] = time.perf_counter() - started
        program = program if program.prompt else program.model_copy(update={"prompt": pending.prompt})
        category = pending.category or edit_category(program, command_kinds(program, self.ctx.states))
        if not self._selected(category):
            progress(self._record(s, 1, "refused", self._not_selected(category), seconds, program=program,
                                  category=category))
            return
        adjustment = ""
        for attempt in range(1, self.config.max_attempts + 1):
            record, adjusted = self._attempt(s, attempt, program, adjustment, seconds)
            progress(record)
            if record.status == "accepted" or adjusted is None:
                if record.status != "accepted" and attempt < self.config.max_attempts:
                    logger.info("%s scenario %d: nothing to adjust; next proposal", self.ctx.log.seq_id, index)
                return
            program, adjustment, seconds = adjusted.program, adjusted.describe(), {}

    def _attempt(self, s: _Scenario, attempt: int, program: EditProgram, adjustment: str, seconds: dict[str, float]
                 ) -> tuple[AttemptRecord, Adjustment | None]:
        """One attempt of ``program``: its record, and the next attempt's program (``None``: none)."""
        ctx, config = self.ctx, self.config
        started = time.perf_counter()
        try:
            edited = apply_edit(ctx, program, config.options)
        except EditRefused as exc:
            seconds["edit"] = time.perf_counter() - started
            kinds = command_kinds(program, ctx.states)
            record = self._record(s, attempt, "refused", _refusal(exc), seconds, program=program,
                                  category=edit_category(program, kinds), adjustment=adjustment)
            if exc.reason == "not_found" and s.pending.target_id is not None:  # say which object was meant
                return record, retarget(program, exc.command_index, s.pending.target_id)
            return record, adjust_program(program, kinds, (), {exc.reason})
        seconds["edit"] = time.perf_counter() - started
        seconds.update(edited.seconds)  # the editor's split of "edit"
        kinds = command_kinds(program, ctx.states, edited)
        category = edit_category(program, kinds)
        s.used_assets |= {a.asset_id.split(VARIANT_SEP, 1)[0] for a in edited.delta.added}

        started = time.perf_counter()
        shown = judge_views(edited, ctx.log, frames=config.judge_frames, max_width=config.judge_width,
                            bev_size=config.bev_size, title=s.pending.prompt)
        request = judge_request_from_edit(edited, shown.renders, shown.bev, visible_pixels=shown.visible_pixels,
                                          prompt=s.pending.prompt, labeller=(ctx.log.ego_poses, ctx.map_ctx))
        seconds["render"] = time.perf_counter() - started

        started = time.perf_counter()
        try:
            verdict = self.client.judge(request)
        except (VLMError, ValueError) as exc:
            seconds["judge"] = time.perf_counter() - started
            self._failed_call(exc)
            record = self._record(s, attempt, "failed", f"vlm_error: judge: {_error(exc)}", seconds, program=program,
                                  category=category, adjustment=adjustment)
            return record, None
        seconds["judge"] = time.perf_counter() - started
        self._answered()

        if edited.validation.ok and verdict.follows_prompt and verdict.plausibility >= config.min_plausibility:
            return self._record(s, attempt, "accepted", "", seconds, program=program, category=category,
                                verdict=verdict, adjustment=adjustment, edited=edited), None
        record = self._record(s, attempt, "rejected", rejection_reason(edited, verdict, config.min_plausibility),
                              seconds, program=program, category=category, verdict=verdict, adjustment=adjustment)
        adjusted = adjust_program(program, kinds, verdict.suggestions,
                                  failure_classes(edited, shown, config.min_visible_pixels),
                                  alternative_asset=asset_alternatives(ctx, s.used_assets))
        return record, adjusted


def mine_sequence(ctx: EditContext, client: VLMClient, config: MiningConfig | None = None, *,
                  views: Sequence[np.ndarray] | None = None, seed_prompts: Iterable[str | Proposal] = (),
                  progress: MiningProgress | None = None) -> MiningResult:
    """Mine one sequence (module docstring).

    Args:
        ctx: the sequence's edit context (never changed).
        client: proposes, translates and judges (e.g. ``RuleBasedVLMClient``, ``OpenAIVLMClient``).
        config: the loop's settings (default :class:`MiningConfig`).
        views: ``[H, W, 3]`` images of the scene the client proposes from (default: the stored scene rendered from
            every camera at the first frame, ``config.judge_width`` wide, or the log's bird's-eye view when it has no
            cameras; rendered only for a client that reads them).
        seed_prompts: prompts tried first (search hits; a :class:`Proposal` keeps its category).
        progress: ``progress(accepted, config.scenarios)`` after each attempt.
    """
    config = config or MiningConfig()
    seq_id = ctx.log.seq_id
    started = time.perf_counter()
    scene = summary(scene_facts(ctx))
    facts_s = time.perf_counter() - started

    def rendered_views() -> Sequence[np.ndarray]:
        return proposal_views(ctx.graph, ctx.log, max_width=config.judge_width, states=ctx.states)

    feed = ProposalFeed(client, scene, views if views is not None else rendered_views, seed_prompts,
                        per_round=config.proposals_per_round, max_rounds=config.max_rounds)
    miner = _Miner(ctx, client, config, scene)
    records: list[AttemptRecord] = []
    prompts: list[str] = []

    def add(record: AttemptRecord) -> None:
        records.append(record)
        if progress is not None:
            progress(sum(r.status == "accepted" for r in records), config.scenarios)

    index = 0
    while sum(r.status == "accepted" for r in records) < config.scenarios:
        if miner.unreachable_in_a_row >= MAX_UNREACHABLE_IN_A_ROW:
            logger.warning("%s: the VLM endpoint could not be reached %d times in a row; the remaining proposals are "
                           "not attempted", seq_id, miner.unreachable_in_a_row)
            break
        pending = feed.take()
        if pending is None:
            break
        if pending.error:
            add(miner.proposing_failed(index, pending))
        else:
            prompts.append(pending.prompt)
            miner.scenario(index, pending, add)
        index += 1
    totals = {stage: sum(r.seconds.get(stage, 0.0) for r in records) for stage in TIMED_STAGES}
    totals["propose"] = facts_s + feed.seconds
    result = MiningResult(seq_id, getattr(client, "name", type(client).__name__), tuple(records), tuple(prompts),
                          totals)
    logger.info("%s: %d attempt(s) over %d proposal(s): %d accepted, %d rejected, %d refused, %d failed (%s)",
                seq_id, len(records), len(prompts), result.count("accepted"), result.count("rejected"),
                result.count("refused"), result.count("failed"),
                ", ".join(f"{k} {v:.1f} s" for k, v in totals.items()))
    return result


__all__ = ["MAX_UNREACHABLE_IN_A_ROW", "MiningConfig", "MiningProgress", "asset_alternatives", "default_client",
           "failure_classes", "mine_sequence", "program_json", "rejection_reason"]
