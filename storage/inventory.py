"""What the store holds per sequence, checked before a stage runs: a complete log, a reconstructed scene, a
language scene (and the store's asset bank), else one clear error naming the sequences and the command that
makes what they lack.

    seq_ids = require_sequences(store)                             # every complete log; an error when none
    seq_ids = require_sequences(store, ["synth-000001"], SCENE)    # that one has a reconstructed scene
    aligned = sequences_with(store, LANGUAGE_SCENE)                # no error: maybe []
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass

from storage.assets import list_asset_banks
from storage.errors import MissingInputError
from storage.language_scenes import list_language_scenes
from storage.logs import list_logs
from storage.scenes import list_scenes
from storage.store import ArtifactStore

#: How a store gets logs (named when it has none).
ADD_LOGS = ("generate synthetic ones (simsplat run --sequences N) or ingest real ones "
            "(simsplat ingest SOURCE PATH, or simsplat ingest auto PATH)")


@dataclass(frozen=True)
class Requirement:
    """An artifact a stage needs per sequence.

    Attributes:
        lacking: the message's start, ``{which}`` replaced by the sequences that lack it ("no language scene of
            {which}").
        directory: where the store keeps it (``logs``, ``scenes``, ``alignment``).
        holders: how the sequences that have it are called in messages ("aligned").
        makes: the command that makes it (``{store}`` is replaced by the store root).
        present: whether a sequence that has a complete log has it (``None``: the log itself is the artifact).
    """

    lacking: str
    directory: str
    holders: str
    makes: str
    present: Callable[[ArtifactStore, str], bool] | None = None

    def has(self, store: ArtifactStore, seq_id: str, logs: AbstractSet[str]) -> bool:
        """Whether ``seq_id`` (among the complete ``logs``) has this artifact."""
        return seq_id in logs and (self.present is None or self.present(store, seq_id))


LOG = Requirement("no complete log {which}", "logs", "available", ADD_LOGS)
SCENE = Requirement("no reconstructed scene of {which}", "scenes", "reconstructed",
                    "run `simsplat reconstruct --store {store}` or `simsplat run`",
                    lambda store, seq_id: bool(list_scenes(store, seq_id)))
LANGUAGE_SCENE = Requirement("no language scene of {which}", "alignment", "aligned",
                             "run `simsplat run` or the alignment stage first: `simsplat align --store {store}`",
                             lambda store, seq_id: bool(list_language_scenes(store, seq_id)))


def sequences_with(store: ArtifactStore, needs: Requirement = LOG) -> list[str]:
    """The sequences of ``store`` that have a complete log and ``needs``' artifact, sorted."""
    logs = list_logs(store)
    complete = frozenset(logs)
    return [s for s in logs if needs.has(store, s, complete)]


def require_sequences(store: ArtifactStore, seq_ids: Sequence[str] | None = None,
                      needs: Requirement = LOG) -> list[str]:
    """``seq_ids`` (default: every sequence that has ``needs``' artifact), each checked to have a complete log and
    that artifact.

    Raises:
        MissingInputError: the store holds no log at all (for ``LOG`` without ``seq_ids``: saying how to add one), no
            sequence has the artifact, or a chosen one lacks it (naming them, those that have it and the command
            that makes it).
    """
    logs = list_logs(store)
    complete = frozenset(logs)  # membership per sequence in O(1): the checks below are per sequence
    if needs is LOG and not logs and not seq_ids:
        raise MissingInputError(f"no driving log in {store.uri(LOG.directory)}: {ADD_LOGS}")
    chosen = list(seq_ids) if seq_ids else [s for s in logs if needs.has(store, s, complete)]
    missing = [s for s in chosen if not needs.has(store, s, complete)]
    if missing or not chosen:
        having = [s for s in logs if needs.has(store, s, complete)]
        which = str(missing) if missing else "any log"
        raise MissingInputError(f"{needs.lacking.format(which=which)} in "
                                f"{store.uri(needs.directory)}; {needs.holders}: {having} "
                                f"({needs.makes.format(store=store.root)})")
    return chosen


def require_asset_bank(store: ArtifactStore, purpose: str = "") -> str:
    """The hash of the store's newest asset bank.

    Raises:
        MissingInputError: the store has none (naming ``purpose``, e.g. "to mine 'synth-000001' with", and the
            command that builds one).
    """
    banks = list_asset_banks(store)
    if not banks:
        why = f" {purpose}" if purpose else ""
        raise MissingInputError(f"no asset bank{why} in {store.uri('assets')} (run `simsplat assets build --store "
                                f"{store.root}` first)")
    return banks[-1]
