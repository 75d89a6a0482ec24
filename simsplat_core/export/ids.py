"""Integer ids of exported tracks and map features, kept from the source where it has integers.

Planner datasets key tracks and map features by integers (WOMD's ``Track.id`` and ``MapFeature.id``). A log
whose object ids are all integers (a Waymo Open Motion scenario, an Argoverse 2 scenario's numeric ids) keeps
them, so an exported scenario's ids match its source's and survive a round trip; otherwise ids are new,
stable integers: the log's objects numbered 1.. in the sorted order of their ids, so every export of the same
log (unedited or any edit of it) gives an object the same id. Agents an edit inserted get the integers after the
largest log id, in the order of their object ids. The ego keeps the source's SDC id when it has one.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

#: ``SceneLog.metadata`` key of the source's SDC track id (Waymo Open Motion scenarios).
SDC_TRACK_ID_KEY = "sdc_track_id"
_INT = re.compile(r"-?\d+")
_SUFFIX_INT = re.compile(r"^[A-Za-z_]+?_(-?\d+)$")


def _as_int(text: str) -> int | None:
    return int(text) if _INT.fullmatch(text) else None


@dataclass(frozen=True)
class TrackIds:
    """Object id -> exported track id, and whether the ids came from the source."""

    ids: Mapping[str, int]
    from_source: bool

    def of(self, object_id: str) -> int:
        try:
            return self.ids[object_id]
        except KeyError:
            raise KeyError(f"no exported track id for object {object_id!r}") from None


def track_ids(log_object_ids: Iterable[str], ego_id: str, other_ids: Sequence[str] = (),
              sdc_source_id: str | None = None) -> TrackIds:
    """Track ids of a log's objects, its ego and the agents an edit added (module docstring).

    Args:
        log_object_ids: every object id of the log (ego excluded).
        ego_id: the ego's object id in the agent states (``"ego"``).
        other_ids: ids of agents not in the log (inserted by an edit), numbered after the log's.
        sdc_source_id: the source's SDC track id (``SceneLog.metadata["sdc_track_id"]``), if any.
    """
    logged = sorted(set(log_object_ids) - {ego_id})
    numbers = [_as_int(o) for o in logged]
    sdc = _as_int(sdc_source_id) if sdc_source_id is not None else None
    from_source = all(n is not None for n in numbers)
    ids: dict[str, int] = {}
    if from_source:
        ids.update({o: int(n) for o, n in zip(logged, numbers) if n is not None})
    else:
        ids.update({o: k for k, o in enumerate(logged, start=1)})
    used = set(ids.values())
    if sdc is None or sdc in used:
        sdc = 0 if 0 not in used else max(used) + 1
    ids[ego_id] = sdc
    used.add(sdc)
    next_id = max(used) + 1
    for o in sorted(set(other_ids) - set(ids)):
        ids[o] = next_id
        next_id += 1
    return TrackIds(ids, from_source)


def feature_ids(source_ids: Sequence[str]) -> dict[str, int]:
    """Map-feature id -> integer: the number after the kind prefix (``"lane_123"`` -> 123, ``"123"`` -> 123)
    when every id has one and they are unique, else 1.. in sorted order of the ids."""
    numbers: list[int | None] = []
    for sid in source_ids:
        plain = _as_int(sid)
        match = _SUFFIX_INT.match(sid)
        numbers.append(plain if plain is not None else (int(match.group(1)) if match else None))
    if all(n is not None for n in numbers) and len(set(numbers)) == len(numbers):
        return {sid: int(n) for sid, n in zip(source_ids, numbers) if n is not None}
    return {sid: k for k, sid in enumerate(sorted(set(source_ids)), start=1)}
