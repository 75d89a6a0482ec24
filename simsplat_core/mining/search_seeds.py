"""Seed proposals for the mining loop from search hits: variants of the scenes where a description holds.

    hits = search_logs(items, "a pedestrian crossing in front of ego").hits
    seeds = hit_variants(hits, kinds={"ped_01": "pedestrian", ...}, per_hit=2)   # seq_id -> [Proposal]
    mine_sequence(ctx, client, config, seed_prompts=seeds[seq_id])

Each hit's subject (its first object that is not the ego) gets the first ``per_hit`` variants of its kind, worded
with the object's id ("make object ped_01 run") so the editor acts on exactly the object the search found, whatever
else in the scene fits the description. Variants change what the subject does (run, stop, delay, brake hard, speed
up) or take it away; a subject met in several hits of one log is varied once.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE
from simsplat_core.search.engine import SearchHit

#: ``(wording, edit category, safety critical)`` per agent kind, most telling first; ``{id}`` is the object id.
VARIANTS: dict[str, tuple[tuple[str, str, bool], ...]] = {
    PEDESTRIAN: (("make object {id} run", "modify_pedestrian", True),
                 ("delay object {id} by 2 s", "modify_pedestrian", False),
                 ("have object {id} stop", "modify_pedestrian", False),
                 ("remove object {id}", "remove", False)),
    VEHICLE: (("object {id} should brake hard", "modify_vehicle", True),
              ("delay object {id} by 2 s", "modify_vehicle", False),
              ("make object {id} drive 10 km/h faster", "modify_vehicle", True),
              ("remove object {id}", "remove", False)),
}
#: Objects of any other kind (static furniture) can only be taken away.
OTHER_VARIANTS: tuple[tuple[str, str, bool], ...] = (("remove object {id}", "remove", False),)
#: ``Proposal.kind`` of a search variant.
SEARCH_VARIANT = "search_variant"


def subject_of(hit: SearchHit) -> str | None:
    """The hit's subject: its first object that is not the ego (``None``: the ego alone)."""
    return next((o for o in hit.object_ids if o != EGO_ID), None)


def hit_variants(hits: Iterable[SearchHit], kinds: Mapping[str, Mapping[str, str]],
                 per_hit: int = 2) -> dict[str, list[Proposal]]:
    """Per sequence, the variant proposals of its hits, in hit order (module docstring).

    Args:
        hits: search hits, best first.
        kinds: per sequence, ``object id -> kind`` (``vehicle`` / ``pedestrian`` / anything else).
        per_hit: variants per hit subject (``>= 1``).

    Raises:
        ValueError: ``per_hit < 1``.
    """
    if per_hit < 1:
        raise ValueError(f"hit_variants: per_hit must be >= 1, got {per_hit}")
    out: dict[str, list[Proposal]] = {}
    varied: set[tuple[str, str]] = set()
    for hit in hits:
        subject = subject_of(hit)
        if subject is None or (hit.seq_id, subject) in varied:
            continue
        varied.add((hit.seq_id, subject))
        kind = kinds.get(hit.seq_id, {}).get(subject, "")
        for wording, category, critical in VARIANTS.get(kind, OTHER_VARIANTS)[:per_hit]:
            out.setdefault(hit.seq_id, []).append(
                Proposal(wording.format(id=subject), category, SEARCH_VARIANT, critical, subject))
    return out


__all__ = ["OTHER_VARIANTS", "SEARCH_VARIANT", "VARIANTS", "hit_variants", "subject_of"]
