"""Mining measures (SIMSplat Table 5 analogue): completion, attempts to acceptance, plausibility, acceptance by edit
category, accepted scenarios re-checked for collisions and off-road agents, and where the time goes.

    outcomes = proposal_outcomes(client, rows)           # rows: the run's edits-table rows (dicts, mining columns)
    failure = stored_failure(trajectories, log_states, sizes, map_ctx)   # re-check of one accepted scenario
    mining = mining_table(outcomes, failures, ran={"rule": True, "openai": False})
    by_category = mining_by_category_table(outcomes)
    stages = mining_stages_table({"rule": seconds}, {"rule": accepted}, cores=2)

Definitions:

* a **proposal** is one scenario of the loop (one ``scenario`` index of a sequence: a prompt proposed by the client
  or seeded, tried up to ``max_attempts`` times with adjusted parameters; a proposal the client refused, or a
  failed proposing call, is a proposal tried and not accepted);
* ``completion`` = accepted proposals / proposals tried;
* ``attempts_mean`` = mean attempt number at which the accepted proposals were accepted (1 = as first proposed;
  Table 5's "mean attempts to acceptance"); NaN when none was accepted;
* ``plausibility_mean`` = mean judged plausibility (1..4) of the accepted scenarios; NaN when none;
* ``accepted_with_failure`` = accepted scenarios in which ANY agent collides (vehicle, pedestrian or static
  object; pairs that overlapped at the same step in the log left out) or leaves the road, re-checked here from the
  stored ``trajectories.parquet`` of the accepted edit with the scenario layer's metrics
  (``scenario.rollout_metrics.scenario_failures`` against the log), not from the loop's own validation flag.

A client that was not run (no endpoint configured) is a row with ``ran = False``, zero counts and NaN rates.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from simsplat_core.eval.table_headlines import Headline
from simsplat_core.eval.table_spec import Column, TableSpec
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.rollout_metrics import ScenarioFailures, scenario_failures

#: ``tables/mining``: one row per VLM client (module docstring for the definitions).
MINING_SPEC = TableSpec("mining", "Mining: completion, attempts, plausibility per VLM client", "VLM client", (
    Column("client", pa.string(), "the VLM client (rule, openai)"),
    Column("ran", pa.bool_(), "the client was run (false: no endpoint configured)"),
    Column("sequences", pa.int64(), "sequences the client mined", "count"),
    Column("prompts", pa.int64(), "proposals tried", "count"),
    Column("accepted", pa.int64(), "proposals accepted", "count"),
    Column("completion", pa.float64(), "accepted / prompts", "share"),
    Column("attempts_mean", pa.float64(), "mean attempt number at which proposals were accepted", "count"),
    Column("plausibility_mean", pa.float64(), "mean judged plausibility of the accepted scenarios (1..4)", ""),
    Column("accepted_with_failure", pa.int64(), "accepted scenarios that collide or leave the road on re-check",
           "count"),
    Column("note", pa.string(), "why the client was not run (\"\": it ran)"),
), keys=("client",), headlines=(Headline("completion"), Headline("plausibility_mean")))
#: ``tables/mining_by_category``: one row per (client, edit category), categories then ``total``.
MINING_BY_CATEGORY_SPEC = TableSpec("mining_by_category", "Mining: acceptance by edit category",
                                    "(client, edit category)", (
    Column("client", pa.string(), "the VLM client"),
    Column("category", pa.string(), "the edit category (unknown: none known; total: all)"),
    Column("prompts", pa.int64(), "proposals tried", "count"),
    Column("accepted", pa.int64(), "proposals accepted", "count"),
    Column("completion", pa.float64(), "accepted / prompts", "share"),
    Column("attempts_mean", pa.float64(), "mean attempt number at which proposals were accepted", "count"),
), keys=("client", "category"))
#: ``tables/mining_stages``: one row per (client, stage), then a ``total`` row per client.
MINING_STAGES_SPEC = TableSpec("mining_stages", "Mining: where the time goes", "(client, stage)", (
    Column("client", pa.string(), "the VLM client"),
    Column("stage", pa.string(), "a stage of the mining loop (MINING_STAGES), or total"),
    Column("seconds", pa.float64(), "wall time of the stage summed over the sequences", "s"),
    Column("share", pa.float64(), "seconds / the client's total seconds", "share"),
    Column("seconds_per_accepted", pa.float64(), "seconds per accepted scenario", "s"),
    Column("accepted_per_hour_per_core", pa.float64(), "accepted scenarios per hour per core (total row only)",
           "1/h/core"),
), keys=("client", "stage"), digits=2, headlines=(Headline("accepted_per_hour_per_core", where=(("stage", "total"),)),))
#: The mining evaluation's tables, in the order they are written.
MINING_SPECS: tuple[TableSpec, ...] = (MINING_SPEC, MINING_BY_CATEGORY_SPEC, MINING_STAGES_SPEC)
#: Stages of ``mining_stages``, in the order of the loop: loading the sequence, proposing (scene facts, views,
#: the client's call), turning prompts into commands, the editor (grounding, applying, refinement, validation),
#: rendering the judge's views, judging, rendering the accepted scenarios for storage (every frame and camera),
#: writing them (encoding, pictures, tables). Their sum is the ``total`` row (the loop's bookkeeping between
#: stages is not timed).
MINING_STAGES: tuple[str, ...] = ("load", "propose", "command", "ground", "apply", "refine", "validate", "render",
                                  "judge", "store_render", "write")
#: Category of a proposal whose category is unknown (a failed proposing call, a prompt nothing could parse).
UNKNOWN_CATEGORY = "unknown"


@dataclass(frozen=True)
class ProposalOutcome:
    """One proposal (scenario) of a mining run.

    Attributes:
        client, seq_id, scenario: which (``scenario`` is the loop's index in the sequence).
        edit_id: the scenario's ``edit_id`` (where an accepted one is stored).
        category: its edit category (:data:`UNKNOWN_CATEGORY` when none is known).
        attempts: attempts made (for an accepted one: the attempt that was accepted).
        accepted: whether an attempt was accepted.
        plausibility: the accepted attempt's judged plausibility (``None``: not accepted or not judged).
    """

    client: str
    seq_id: str
    scenario: int
    edit_id: str
    category: str
    attempts: int
    accepted: bool
    plausibility: int | None = None


def group_proposals(rows: Iterable[Mapping[str, Any]]) -> dict[tuple[str, int], list[Mapping[str, Any]]]:
    """Edits-table rows of a mining run grouped by proposal: ``(seq_id, scenario) -> its rows`` in the rows'
    order, proposals in first-seen order.

    Raises:
        ValueError: a row without the mining columns (naming the row's ``edit_id``).
    """
    grouped: dict[tuple[str, int], list[Mapping[str, Any]]] = {}
    for row in rows:
        if row.get("scenario") is None or not row.get("mining_status"):
            raise ValueError(f"edits row {row.get('edit_id')!r}: no mining columns (scenario, mining_status); "
                             "not a row of a mining run")
        grouped.setdefault((str(row["seq_id"]), int(row["scenario"])), []).append(row)
    return grouped


def proposal_outcomes(client: str, rows: Iterable[Mapping[str, Any]]) -> list[ProposalOutcome]:
    """The proposals of one client's run from its edits-table rows (keys ``seq_id``, ``edit_id``, ``scenario``,
    ``category``, ``mining_status``, ``plausibility``; rows of one proposal in attempt order), in first-seen order.

    Raises:
        ValueError: a row without the mining columns (naming the row's ``edit_id``).
    """
    out = []
    for (seq_id, scenario), attempts in group_proposals(rows).items():
        accepted = [k for k, r in enumerate(attempts) if r["mining_status"] == "accepted"]
        last = attempts[accepted[0]] if accepted else attempts[-1]
        category = next((str(r["category"]) for r in reversed(attempts) if r.get("category")), UNKNOWN_CATEGORY)
        out.append(ProposalOutcome(
            client=client, seq_id=seq_id, scenario=scenario, edit_id=str(last["edit_id"]), category=category,
            attempts=(accepted[0] + 1) if accepted else len(attempts), accepted=bool(accepted),
            plausibility=None if not accepted or last.get("plausibility") is None else int(last["plausibility"])))
    return out


# ----------------------------------------------------------------------------------------------- re-check
def states_from_trajectories(trajectories: pa.Table, log_states: AgentStates,
                             sizes: Mapping[str, Sequence[float]] | None = None) -> AgentStates:
    """The agents of a stored ``trajectories`` table (DESIGN's table: one row per agent and valid step) on the
    log's steps.

    Args:
        trajectories: columns ``object_id``, ``category``, ``step`` (log frame index), ``x``, ``y``, ``heading``,
            ``speed``, ``source``.
        log_states: the log's agents: their steps (``frame_idx``, ``times``) and the box size of every log agent.
        sizes: box ``(length, width, height)`` by object id for agents whose box is not the log's (inserted ones,
            replaced ones: their asset's box).

    Raises:
        ValueError: a step not among the log's frames, or an agent whose box size is known nowhere (named).
    """
    sizes = dict(sizes or {})
    oids = [str(o) for o in trajectories.column("object_id").to_pylist()]
    order = list(dict.fromkeys(oids))
    row_of = {o: k for k, o in enumerate(order)}
    step_of = {int(f): k for k, f in enumerate(log_states.frame_idx.tolist())}
    frames = trajectories.column("step").to_pylist()
    missing = sorted({int(f) for f in frames} - set(step_of))
    if missing:
        raise ValueError(f"trajectories: steps {missing[:5]} are not frames of the log {sorted(step_of)[:3]}...")
    a, t = len(order), log_states.num_steps
    rows = np.fromiter((row_of[o] for o in oids), np.int64, len(oids))
    steps = np.fromiter((step_of[int(f)] for f in frames), np.int64, len(frames))
    xy = np.zeros((a, t, 2))
    heading, speed = np.zeros((a, t)), np.zeros((a, t))
    valid = np.zeros((a, t), dtype=bool)
    xy[rows, steps, 0] = trajectories.column("x").to_numpy()
    xy[rows, steps, 1] = trajectories.column("y").to_numpy()
    heading[rows, steps] = trajectories.column("heading").to_numpy()
    speed[rows, steps] = trajectories.column("speed").to_numpy()
    valid[rows, steps] = True
    categories, sources = [""] * a, [""] * a
    for oid, cat, src in zip(oids, trajectories.column("category").to_pylist(),
                             trajectories.column("source").to_pylist()):
        categories[row_of[oid]], sources[row_of[oid]] = str(cat), str(src)
    size = np.zeros((a, 3))
    for oid, k in row_of.items():
        if oid in sizes:
            size[k] = np.asarray(sizes[oid], np.float64).reshape(3)
        elif oid in log_states.object_ids:
            size[k] = log_states.size[log_states.index(oid)]
        else:
            raise ValueError(f"trajectories: no box size for agent {oid!r} (not in the log, none given)")
    return AgentStates(object_ids=tuple(order), categories=tuple(categories), sources=tuple(sources),
                       node_ids=np.full(a, -1, np.int64), frame_idx=np.asarray(log_states.frame_idx),
                       times=np.asarray(log_states.times), xy=xy, z=np.zeros((a, t)), heading=heading, speed=speed,
                       size=size, valid=valid)


def stored_failure(trajectories: pa.Table, log_states: AgentStates, sizes: Mapping[str, Sequence[float]],
                   map_ctx: MapContext) -> ScenarioFailures:
    """Collisions and off-road agents of a stored scenario, re-checked from its ``trajectories`` table
    (:func:`states_from_trajectories`) against the log (``rollout_metrics.scenario_failures`` over every agent,
    the log as baseline)."""
    states = states_from_trajectories(trajectories, log_states, sizes)
    return scenario_failures(states, map_ctx, baseline=log_states)


def collides_or_offroad(failure: ScenarioFailures) -> bool:
    """Whether any agent collides (vehicle, pedestrian, static object) or leaves the road."""
    return bool(failure.collision_vehicle or failure.collision_pedestrian or failure.collision_static
                or failure.offroad)


# ----------------------------------------------------------------------------------------------- tables
def _mean(values: Sequence[float]) -> float:
    return float(statistics.fmean(values)) if values else math.nan


def _rate(num: float, den: float) -> float:
    return num / den if den else math.nan


def mining_table(outcomes: Sequence[ProposalOutcome], failures: Mapping[tuple[str, str, str], bool],
                 clients: Mapping[str, str]) -> pa.Table:
    """One row per client of ``clients`` (name -> ``""`` when it ran, else why it was not run), in that order
    (:data:`MINING_SPEC`; module docstring for the definitions).

    Args:
        outcomes: every proposal of every client.
        failures: ``(client, seq_id, edit_id) -> collides or leaves the road`` for the accepted scenarios.

    Raises:
        KeyError: an accepted scenario without its re-check (named).
    """
    data: dict[str, list[Any]] = {name: [] for name in MINING_SPEC.column_names}
    for client, note in clients.items():
        mine = [o for o in outcomes if o.client == client]
        accepted = [o for o in mine if o.accepted]
        for o in accepted:
            if (client, o.seq_id, o.edit_id) not in failures:
                raise KeyError(f"accepted scenario {o.edit_id} of {o.seq_id} ({client}) was not re-checked")
        ran = not note
        data["client"].append(client)
        data["ran"].append(ran)
        data["sequences"].append(len({o.seq_id for o in mine}))
        data["prompts"].append(len(mine))
        data["accepted"].append(len(accepted))
        data["completion"].append(_rate(len(accepted), len(mine)))
        data["attempts_mean"].append(_mean([o.attempts for o in accepted]))
        data["plausibility_mean"].append(_mean([o.plausibility for o in accepted if o.plausibility is not None]))
        data["accepted_with_failure"].append(sum(failures[(client, o.seq_id, o.edit_id)] for o in accepted))
        data["note"].append(note)
    return pa.Table.from_pydict(data, schema=MINING_SPEC.schema)


def mining_by_category_table(outcomes: Sequence[ProposalOutcome], clients: Sequence[str]) -> pa.Table:
    """Per client (in order) and edit category (``EDIT_CATEGORIES``, then others seen -- e.g.
    :data:`UNKNOWN_CATEGORY` --, then ``total``): proposals, accepted, completion and mean attempts to acceptance
    (:data:`MINING_BY_CATEGORY_SPEC`). A client that proposed nothing has only its ``total`` row."""
    data: dict[str, list[Any]] = {name: [] for name in MINING_BY_CATEGORY_SPEC.column_names}
    for client in clients:
        mine = [o for o in outcomes if o.client == client]
        present = {o.category for o in mine}
        categories = [*EDIT_CATEGORIES, *sorted(present - set(EDIT_CATEGORIES))] if mine else []
        for category in (*categories, "total"):
            chosen = mine if category == "total" else [o for o in mine if o.category == category]
            accepted = [o for o in chosen if o.accepted]
            data["client"].append(client)
            data["category"].append(category)
            data["prompts"].append(len(chosen))
            data["accepted"].append(len(accepted))
            data["completion"].append(_rate(len(accepted), len(chosen)))
            data["attempts_mean"].append(_mean([o.attempts for o in accepted]))
    return pa.Table.from_pydict(data, schema=MINING_BY_CATEGORY_SPEC.schema)


def mining_stages_table(seconds: Mapping[str, Mapping[str, float]], accepted: Mapping[str, int],
                        cores: int) -> pa.Table:
    """Where the time goes, per client (``seconds``: client -> stage -> seconds summed over the sequences, the
    stages of :data:`MINING_STAGES`): one row per stage with its seconds, its share of the total and its seconds
    per accepted scenario, then a ``total`` row with ``accepted_per_hour_per_core`` = accepted scenarios /
    (total hours x ``cores``) (NaN on the stage rows) (:data:`MINING_STAGES_SPEC`).

    Raises:
        ValueError: ``cores`` < 1.
    """
    if cores < 1:
        raise ValueError(f"mining_stages_table: cores must be >= 1, got {cores}")
    data: dict[str, list[Any]] = {name: [] for name in MINING_STAGES_SPEC.column_names}
    for client, per in seconds.items():
        total = sum(float(per.get(s, 0.0)) for s in MINING_STAGES)
        n = int(accepted.get(client, 0))
        for stage in (*MINING_STAGES, "total"):
            value = total if stage == "total" else float(per.get(stage, 0.0))
            data["client"].append(client)
            data["stage"].append(stage)
            data["seconds"].append(value)
            data["share"].append(_rate(value, total) if total > 0 else math.nan)
            data["seconds_per_accepted"].append(value / n if n else math.nan)
            data["accepted_per_hour_per_core"].append(
                (n / (total / 3600.0 * cores) if total > 0 else math.nan) if stage == "total" else math.nan)
    return pa.Table.from_pydict(data, schema=MINING_STAGES_SPEC.schema)


__all__ = ["MINING_BY_CATEGORY_SPEC", "MINING_SPEC", "MINING_SPECS", "MINING_STAGES", "MINING_STAGES_SPEC",
           "UNKNOWN_CATEGORY", "ProposalOutcome", "collides_or_offroad", "group_proposals", "mining_by_category_table",
           "mining_table", "mining_stages_table", "proposal_outcomes", "states_from_trajectories", "stored_failure"]
