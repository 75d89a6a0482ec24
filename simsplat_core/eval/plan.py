"""Which evaluation tables a store's contents allow, each with the sequences it uses or why it is skipped.

    contents = StoreContents(logs=("s0", "s1"), synthetic=("s0", "s1"), ground_truth=("s0",), scenes=("s0",),
                             aligned=("s0",), asset_bank=True, timed_runs=("evalmine-rule-...",))
    for step in plan_evaluation(contents):
        step.group, step.tables, step.seq_ids, step.skip      # skip: "" when the step runs

A step is one evaluation (one task) writing one or more tables; a skipped step has a reason that says what the
store lacks, never an error.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The evaluations, in the order they run, and the tables each writes (names of ``table_registry.EVAL_TABLES``).
EVAL_GROUPS: dict[str, tuple[str, ...]] = {
    "reconstruction": ("reconstruction",),
    "throughput": ("throughput",),
    "grounding": ("grounding", "grounding_ablation", "grounding_outcomes"),
    "editing": ("editing", "editing_infeasible", "edit_fidelity", "editing_outcomes"),
    "motion": ("motion", "motion_outcomes"),
    "mining": ("mining", "mining_by_category", "mining_stages"),
    "search": ("search",),
}


@dataclass(frozen=True)
class StoreContents:
    """What a store holds, as far as the evaluations care.

    Attributes:
        logs: every complete log.
        synthetic: logs of the synthetic world (its scripted behaviours are the search's ground truth).
        ground_truth: synthetic logs with camera images (captions and instance masks: grounding, editing).
        scenes: logs with a reconstructed scene.
        aligned: logs with a language scene.
        asset_bank: an asset bank is stored (editing, motion edits and mining insert from it).
        timed_runs: stored runs with recorded stage timings (mined edit runs, aligner models).
    """

    logs: tuple[str, ...] = ()
    synthetic: tuple[str, ...] = ()
    ground_truth: tuple[str, ...] = ()
    scenes: tuple[str, ...] = ()
    aligned: tuple[str, ...] = ()
    asset_bank: bool = False
    timed_runs: tuple[str, ...] = ()


@dataclass(frozen=True)
class EvalStep:
    """One evaluation of the plan.

    Attributes:
        group: a key of :data:`EVAL_GROUPS`.
        tables: the tables it writes.
        seq_ids: the sequences it evaluates (empty for store-wide tables).
        skip: why it does not run (``""``: it runs).
    """

    group: str
    tables: tuple[str, ...]
    seq_ids: tuple[str, ...] = ()
    skip: str = ""

    @property
    def runs(self) -> bool:
        return not self.skip


def _step(group: str, seq_ids: tuple[str, ...], lacking: str) -> EvalStep:
    return EvalStep(group, EVAL_GROUPS[group], seq_ids, lacking)


def plan_evaluation(contents: StoreContents, groups: tuple[str, ...] | None = None) -> list[EvalStep]:
    """The steps of :data:`EVAL_GROUPS` (or ``groups`` of them, in that order), each running or skipped with a reason.

    Raises:
        KeyError: an unknown group (naming the known ones).
    """
    chosen = tuple(EVAL_GROUPS) if groups is None else tuple(groups)
    unknown = [g for g in chosen if g not in EVAL_GROUPS]
    if unknown:
        raise KeyError(f"unknown evaluation(s) {unknown}; known: {list(EVAL_GROUPS)}")
    aligned_truth = tuple(s for s in contents.ground_truth if s in contents.aligned)
    aligned_any = tuple(s for s in contents.logs if s in contents.aligned)
    no_aligned_truth = "" if aligned_truth else "no aligned synthetic log with ground-truth images"
    no_bank = "" if contents.asset_bank else "no asset bank (simsplat assets build)"
    reasons = {
        "reconstruction": (contents.scenes, "" if contents.scenes else "no reconstructed scene"),
        "throughput": (contents.scenes, "" if contents.scenes or contents.timed_runs
                       else "no recorded stage timings (no reconstructed scene, aligner or mined run)"),
        "grounding": (aligned_truth, no_aligned_truth),
        "editing": (aligned_truth, no_aligned_truth or no_bank),
        "motion": (aligned_truth, no_aligned_truth or no_bank),
        "mining": (aligned_any, ("" if aligned_any else "no aligned log") or no_bank),
        "search": (contents.synthetic, "" if contents.synthetic else "no synthetic log (the search's ground truth)"),
    }
    return [_step(g, *reasons[g]) for g in chosen]


__all__ = ["EVAL_GROUPS", "EvalStep", "StoreContents", "plan_evaluation"]
