"""Task that builds the asset bank of a store: cut-outs of every reconstructed scene + procedural statics.

Thin: find the sources (each sequence's newest reconstructed scene and the language scene built from it,
if any), key the bank by them and the config, skip when a complete bank with that key is stored, else
load each scene, cut its assets out (``editing.assets.cutout``), add the procedural statics
(``editing.assets.procedural``), draw the contact sheet and write it all with ``storage.assets``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.cutout import CutoutConfig, cutout_assets
from simsplat_core.editing.assets.procedural import STATIC_KINDS, procedural_assets
from simsplat_core.scene import SceneGraph
from simsplat_core.viz.asset_sheet import asset_contact_sheet
from simsplat_core.viz.images import encode_png
from storage import ArtifactStore, config_settings, content_key, intact_marker, list_scenes, read_scene, read_scene_log
from storage.assets import (
    ASSET_BANK_FORMAT_VERSION,
    bank_dir,
    list_asset_banks,
    read_asset_bank,
    read_asset_index,
    read_bank_manifest,
    write_asset_bank,
)
from storage.inventory import SCENE, require_sequences, sequences_with
from storage.language_scenes import list_language_scenes, read_language_manifest, read_language_scene
from storage.pictures import write_png
from tasks.progress import StepProgress
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)

#: Version of the bank-building stage; bump it to rebuild every bank.
BANK_VERSION = "assets-v1"
SHEET_FILE = "contact_sheet.png"


@dataclass(frozen=True)
class AssetSource:
    """One scene the bank cuts assets out of.

    Attributes:
        seq_id: the sequence.
        scene_hash: its newest reconstructed scene.
        language: ``(model_hash, language_hash)`` of the newest language scene built from that scene, or
            ``None`` (captions then come from the log or the built-in captioner).
    """

    seq_id: str
    scene_hash: str
    language: tuple[str, str] | None = None


@dataclass(frozen=True)
class BuiltBank:
    """What ``build_asset_bank`` returns (small).

    Attributes:
        bank_hash: the content key of the sources and config; the bank's directory name.
        uri: ``<store>/assets/<bank_hash>``.
        assets: number of assets; by_category: per category.
        gaussians, bytes: totals stored.
        skipped: True when a complete bank with this hash was already stored.
        report: the cut-out filter's lines per scene (empty when skipped).
        sheet_uri: the contact sheet (``""`` when none was drawn).
        seconds: wall time (0 when skipped).
    """

    bank_hash: str
    uri: str
    assets: int
    by_category: dict[str, int]
    gaussians: int
    bytes: int
    skipped: bool
    report: list[str] = field(default_factory=list)
    sheet_uri: str = ""
    seconds: float = 0.0


def asset_sources(store: ArtifactStore, seq_ids: list[str] | None = None) -> list[AssetSource]:
    """The newest reconstructed scene (and its language scene) of each of ``seq_ids`` (default: every log
    with a reconstructed scene).

    Raises:
        MissingInputError: a chosen sequence has no complete reconstructed scene (naming it and those that do).
    """
    chosen = require_sequences(store, seq_ids, SCENE) if seq_ids else sequences_with(store, SCENE)
    sources = []
    for seq_id in chosen:
        scene_hash = list_scenes(store, seq_id)[-1]
        language = next(((m, h) for m, h in list_language_scenes(store, seq_id)
                         if (read_language_manifest(store, m, seq_id, h) or {}).get("scene_hash") == scene_hash), None)
        sources.append(AssetSource(seq_id, scene_hash, language))
    return sources


def bank_key(sources: list[AssetSource], config: CutoutConfig) -> str:
    """Content key of a bank: its sources, the cut-out filter, the procedural catalogue and the versions."""
    return content_key("asset-bank", BANK_VERSION, ASSET_BANK_FORMAT_VERSION, [asdict(s) for s in sources],
                       config_settings(config), sorted(STATIC_KINDS.values(), key=lambda k: k.subtype))


def _cut_out(store: ArtifactStore, source: AssetSource, config: CutoutConfig) -> tuple[list, list[str]]:
    graph = SceneGraph.from_records(read_scene(store, source.seq_id, source.scene_hash).records)
    log = read_scene_log(store, source.seq_id, load_images=False)
    language = None
    if source.language is not None:
        model_hash, language_hash = source.language
        language = read_language_scene(store, source.seq_id, model_hash, language_hash, with_records=False).scene
    assets, report = cutout_assets(graph, log.objects, log.tracks, seq_id=source.seq_id, language=language,
                                   config=config, scene_hash=source.scene_hash)
    return assets, report.lines()


def _stored(store: ArtifactStore, key: str, manifest: dict) -> BuiltBank:
    files = manifest.get("files", [])
    return BuiltBank(key, store.uri(bank_dir(key)), int(manifest.get("assets", 0)),
                     dict(manifest.get("by_category", {})), int(manifest.get("gaussians", 0)),
                     int(manifest.get("bytes", 0)), True,
                     sheet_uri=store.uri(f"{bank_dir(key)}/{SHEET_FILE}") if SHEET_FILE in files else "")


@task(name="build-asset-bank", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def build_asset_bank(store_root: str, seq_ids: list[str] | None = None, config: CutoutConfig | None = None,
                     sheet: bool = True) -> BuiltBank:
    """Build (or find) the asset bank of ``<store>``'s reconstructed scenes under ``<store>/assets/<bank_hash>``.

    Args:
        seq_ids: sequences to cut assets out of (default: every one with a reconstructed scene).
        config: the cut-out filter (default ``CutoutConfig()``).
        sheet: also draw the contact sheet (``contact_sheet.png`` in the bank directory).

    Progress (``tasks.progress``): ``"asset bank: cut out"`` per scene, ``"asset bank: contact sheet"`` per tile.

    Raises:
        MissingInputError: a chosen sequence has no reconstructed scene.
    """
    store = ArtifactStore(store_root)
    config = config or CutoutConfig()
    sources = asset_sources(store, seq_ids)
    key = bank_key(sources, config)
    manifest = intact_marker(store, bank_dir(key), key)
    if manifest is not None:
        logger.info("asset bank %s already built, skipping", key[:12])
        return _stored(store, key, manifest)
    start = time.perf_counter()
    assets, report = [], []
    cut_progress = StepProgress("asset bank: cut out", headline="")
    for k, source in enumerate(sources):
        cut, lines = _cut_out(store, source, config)
        assets += cut
        report += lines
        cut_progress(k + 1, len(sources))
    assets += procedural_assets()
    bank = AssetBank.from_assets(assets, key)
    extra = {}
    if sheet:
        tiles = StepProgress("asset bank: contact sheet", headline="")
        extra[SHEET_FILE] = encode_png(asset_contact_sheet(bank.assets, progress=lambda done, n: tiles(done, n)))
    provenance = {"sources": [asdict(s) for s in sources], "cutout": config_settings(config),
                  "bank_version": BANK_VERSION}
    write_asset_bank(store, bank, provenance=provenance, extra_files=extra)
    built = _stored(store, key, read_bank_manifest(store, key) or {})
    seconds = time.perf_counter() - start
    logger.info("built asset bank %s: %d assets in %.1f s", key[:12], len(bank), seconds)
    return BuiltBank(built.bank_hash, built.uri, built.assets, built.by_category, built.gaussians, built.bytes,
                     False, report, built.sheet_uri, seconds)


@dataclass(frozen=True)
class AssetListing:
    """The store's asset banks and the assets of one (what ``simsplat assets list`` shows).

    Attributes:
        banks: per bank, oldest first: ``bank_hash``, ``assets``, ``by_category``, ``written_at`` (from its manifest).
        bank_hash: the bank listed (the newest unless one was asked for).
        assets: one dict per asset of that bank (``storage.assets.read_asset_index``).
        uri: where the store keeps its banks (``<store>/assets``).
    """

    banks: list[dict[str, Any]]
    bank_hash: str
    assets: list[dict[str, Any]]
    uri: str


def list_assets(store_root: str, bank_hash: str | None = None) -> AssetListing:
    """The store's banks and the assets of ``bank_hash`` (a unique prefix is enough; default: the newest).

    Raises:
        FileNotFoundError, ValueError: no (such) complete bank (naming ``simsplat assets build``), an ambiguous prefix.
    """
    store = ArtifactStore(store_root)
    full, rows = read_asset_index(store, bank_hash)
    banks = [{"bank_hash": h, **{k: (read_bank_manifest(store, h) or {}).get(k) for k in
                                  ("assets", "by_category", "written_at")}} for h in list_asset_banks(store)]
    return AssetListing(banks, full, rows, store.uri("assets"))


@dataclass(frozen=True)
class AssetSheet:
    """A drawn contact sheet: where it went, of which bank, how many assets."""

    uri: str
    bank_hash: str
    assets: int


def draw_asset_sheet(store_root: str, out: str, bank_hash: str | None = None, columns: int = 8) -> AssetSheet:
    """Draw a bank's contact sheet (every asset rendered alone from the same 3/4 view, with its caption;
    ``columns`` tiles per row) to ``out`` (a ``.png`` path or URI). Progress: ``"contact sheet"`` per tile.

    Raises:
        FileNotFoundError, ValueError: no (such) complete bank, an ambiguous prefix; ``out`` is not a ``.png``.
    """
    bank = read_asset_bank(ArtifactStore(store_root), bank_hash)
    tiles = StepProgress("contact sheet", headline="")
    picture = asset_contact_sheet(bank.assets, columns=columns, progress=lambda done, n: tiles(done, n))
    return AssetSheet(write_png(out, picture), bank.bank_hash, len(bank))


__all__ = ["BANK_VERSION", "AssetListing", "AssetSheet", "AssetSource", "BuiltBank", "asset_sources", "bank_key",
           "build_asset_bank", "draw_asset_sheet", "list_assets"]
