"""Mining once per log and settings: the settings key, which sequences still need mining, and the ledger record.

A run mines a sequence only when the store's mining ledger (``storage.mining_ledger``) has no record of it for the
run's **mining settings key**, or has one for another version of the sequence. The key is a content key of what
decides the scenarios: accepted scenarios wanted per sequence, attempts per proposal, the VLM client kind and its
model, the seed, and the key of the mining configuration (saved searches, seed prompts, categories) when one is
used. A record matches the sequence when it names the same stored log (content key) and the same reconstructed
scene. The language scene is recorded but not matched: it changes for every log whenever the store gains a log
(the motion aligner trains on all of them), and re-mining the whole store for each new log is what the ledger is
there to avoid. Another K, seed, client or configuration is another key, so the sequences are mined again.

The ledger record is written by the mining task after the sequence's edits and edits-table rows are stored
(``record_mined``), so a run killed in between re-mines that sequence next time and nothing is counted twice.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from storage import ArtifactStore, content_key, require_log_manifest
from storage.mining_ledger import LedgerRecord, LedgerScenario, read_ledger_record, write_ledger_record
from storage.run_records import utc_now
from tasks.align import StoredLanguageScene

logger = logging.getLogger(__name__)

#: Version of the ledger's key; bump it to mine every sequence again.
LEDGER_VERSION = "mining-ledger-v1"


class MiningSettings(Protocol):
    """What a run's mining plan must say for its ledger key (``flows.pipeline.MiningPlan`` satisfies it)."""

    @property
    def per_sequence(self) -> int: ...

    @property
    def max_attempts(self) -> int: ...

    @property
    def vlm(self) -> str: ...

    @property
    def seed(self) -> int: ...


def vlm_model(vlm: str) -> str:
    """The model behind the VLM client ``vlm``: ``""`` for the built-in rule-based client, the configured model
    (``SIMSPLAT_VLM_MODEL``) for ``"openai"``.

    Raises:
        VLMError: ``"openai"`` without an endpoint configured.
    """
    if vlm != "openai":
        return ""
    from simsplat_core.vlm.openai_chat import OpenAIChatConfig

    return OpenAIChatConfig.from_env().model


@dataclass(frozen=True)
class LedgerSettings:
    """The mining settings a ledger key covers (module docstring).

    Attributes:
        per_sequence, max_attempts, vlm, seed: the mining plan's.
        vlm_model: the model behind ``vlm`` (``vlm_model``).
        config_key: the mining configuration's content key (``""``: none).
    """

    per_sequence: int
    max_attempts: int
    vlm: str
    vlm_model: str
    seed: int
    config_key: str = ""

    @property
    def key(self) -> str:
        """The settings' content key: the ledger folder of the sequences mined with them."""
        return content_key("mining-settings", LEDGER_VERSION, self)


def ledger_settings(plan: MiningSettings, config_key: str = "") -> LedgerSettings:
    """``plan``'s ledger settings, with the mining configuration's key ``config_key`` (``""``: none).

    Raises:
        VLMError: ``plan.vlm`` is ``"openai"`` without an endpoint configured.
    """
    return LedgerSettings(int(plan.per_sequence), int(plan.max_attempts), plan.vlm, vlm_model(plan.vlm),
                          int(plan.seed), config_key)


def _log_key(store: ArtifactStore, seq_id: str) -> str:
    return str(require_log_manifest(store, seq_id, "to mine")["key"])


@dataclass(frozen=True)
class LedgerSplit:
    """Sequences to mine now and those mined before with the same settings (with their records), each in the order
    given."""

    to_mine: tuple[str, ...]
    mined: tuple[LedgerRecord, ...]


def split_by_ledger(store_root: str, candidates: Sequence[StoredLanguageScene], settings_key: str) -> LedgerSplit:
    """Sort the sequences of ``candidates`` (their language scenes) into those to mine and those the ledger has for
    ``settings_key`` (same stored log, same scene: module docstring).

    Raises:
        FileNotFoundError: a candidate's log is not in the store (named).
        CorruptArtifactError: a ledger record is garbled (named).
    """
    store = ArtifactStore(store_root)
    to_mine: list[str] = []
    mined: list[LedgerRecord] = []
    for scene in candidates:
        record = read_ledger_record(store, settings_key, scene.seq_id)
        if record is not None and (record.log_key, record.scene_hash) == (_log_key(store, scene.seq_id),
                                                                          scene.scene_hash):
            mined.append(record)
        else:
            to_mine.append(scene.seq_id)
    return LedgerSplit(tuple(to_mine), tuple(mined))


def mined_reason(record: LedgerRecord) -> str:
    """Why a sequence is not mined again: ``"mined by run R with these settings (N accepted: e1, e2)"``."""
    ids = ", ".join(s.edit_id for s in record.scenarios)
    return (f"mined by run {record.run_id} with these settings ({len(record.scenarios)} accepted"
            f"{': ' + ids if ids else ''})")


def not_exported_reason(record: LedgerRecord) -> str:
    """Why a sequence mined before exports nothing now: its scenarios belong to the run that mined it."""
    return f"no new scenario (mined by run {record.run_id})"


@dataclass(frozen=True)
class MinedSequence:
    """What the mining task tells the ledger about one sequence it mined and stored.

    Attributes:
        seq_id, run_id: the sequence and the run that mined it.
        log_key, scene_hash, language_hash: what it was mined on (``scene_hash`` ``""``: a log without images).
        attempts: attempts made; scenarios: the accepted ones as ``(edit_id, prompt, category)``.
    """

    seq_id: str
    run_id: str
    log_key: str
    scene_hash: str
    language_hash: str
    attempts: int
    scenarios: tuple[tuple[str, str, str], ...]


def record_mined(store: ArtifactStore, settings: LedgerSettings, mined: MinedSequence) -> LedgerRecord:
    """Write the ledger record of ``mined`` under ``settings`` (call it once the sequence's edits are stored)."""
    record = LedgerRecord(settings.key, mined.seq_id, mined.log_key, mined.scene_hash, mined.language_hash,
                          mined.run_id, utc_now(), mined.attempts,
                          tuple(LedgerScenario(*s) for s in mined.scenarios), dataclasses.asdict(settings))
    write_ledger_record(store, record)
    logger.info("%s: ledgered as mined by run %s (settings %s)", mined.seq_id, mined.run_id, settings.key[:12])
    return record
