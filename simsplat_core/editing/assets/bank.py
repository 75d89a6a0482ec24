"""The asset bank: insertable objects and their retrieval from an ``AssetSpec``.

    bank = AssetBank.from_assets([*cut_outs, *procedural_assets()])
    taxi = bank.retrieve(AssetSpec(description="a yellow taxi", category="vehicle", color="yellow"), encoder)
    taxi.label      # "a yellow sedan (recoloured from synth-000000.veh_01)" when the bank has no yellow car

**Retrieval** (:meth:`AssetBank.retrieve`) narrows the bank by hard constraints, then ranks by E5:

1. ``asset_id`` given: that asset (a variant id ``<id>~<colour>`` / ``<id>~<l>x<w>x<h>`` is derived).
2. Category, subtype and colour come from the spec, or -- when it leaves them out -- from the words
   of its description (the query lexicon's nouns ``grounding.parse.NOUNS``, the procedural kinds' names and
   aliases, and ``grounding.parse.COLOR_SYNONYMS``). A subtype fits an asset's when it names it, a kind it
   belongs to (``grounding.lexicon.SUBTYPE_FIT`` with factor 1: "car" fits sedan, hatchback and SUV) or a
   group of procedural kinds (``editing.assets.procedural.STATIC_GROUPS``: "barrier" fits both barriers).
3. Size (``size_m``): a cut-out fits when every side is within ``SIZE_TOLERANCE`` (relative, at least
   ``SIZE_TOLERANCE_M``) of the wanted one; a procedural asset fits when it can be rebuilt at that size
   (``editing.assets.procedural.RESIZE_RANGE``) and is; a box-only asset (``editing.assets.boxes``) is made that size.
4. Colour: assets of that colour come first (a pedestrian's top, or its trousers when the description
   names the colour for them only; among those, ones whose other garment is the other named colour first);
   when the type exists but not in that colour, the best one is *recoloured* (``editing.assets.colors.recolored``;
   procedural assets are rebuilt in the colour, box-only ones only renamed), and the variant records
   ``recoloured_from``.
5. Ranking: cosine of the description (E5 query) with each caption (E5 passage, embeddings cached per
   encoder; when recolouring, the captions as they will read in the new colour), plus ``QUALITY_WEIGHT`` x
   the asset's side coverage (``seen_from`` picks one side: the one the camera will see), for pedestrians
   asked to be ``walking``, ``WALKING_BONUS`` for sources that walked, and with no colour asked,
   ``CANONICAL_BONUS`` for procedural assets in their usual colour; ties go to more Gaussians, then the id.

When nothing fits, :class:`EditRefused` (``reason="no_asset"``) says what was asked and lists what the
bank has of that category.
"""

from __future__ import annotations

import hashlib
import logging
import re
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
import torch

from simsplat_core.color_names import COLOR_NAMES
from simsplat_core.editing.assets.colors import EXPOSURE_TAG, exposed, recolored
from simsplat_core.editing.assets.procedural import (
    RESIZE_RANGE,
    STATIC_GROUPS,
    STATIC_KINDS,
    procedural_asset,
    static_subtype_for,
)
from simsplat_core.editing.assets.record import (
    ASSET_CATEGORIES,
    LOWER_COLOR,
    RECOLOURED_FROM,
    RESIZED_FROM,
    VARIANT_SEP,
    Asset,
    f32,
)
from simsplat_core.editing.commands import AssetSpec
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.appearance.captioner import caption_text
from simsplat_core.language.grounding.lexicon import SUBTYPE_FIT
from simsplat_core.language.grounding.parse import COLOR_SYNONYMS, NOUNS, parse_query
from simsplat_core.language.text import TextEncoder

logger = logging.getLogger(__name__)

#: A cut-out fits a wanted size when each side differs by at most this share (or ``SIZE_TOLERANCE_M``).
SIZE_TOLERANCE = 0.25
SIZE_TOLERANCE_M = 0.3
#: Weight of an asset's side coverage (``attributes["coverage"]``, in [0, 1]) added to its similarity.
QUALITY_WEIGHT = 0.02
#: Added to a procedural asset in its kind's first (usual) colour when no colour is asked for.
CANONICAL_BONUS = 0.03
#: Added to the score of a pedestrian that walked (``Asset.walked_m``) when a walking one is asked for.
WALKING_BONUS = 0.05
Side = Literal["front", "back", "left", "right"]
_HASH = re.compile(r"^[0-9a-f]{8,64}$")
_SIZE_RX = re.compile(r"^(\d+(?:\.\d+)?)x(\d+(?:\.\d+)?)x(\d+(?:\.\d+)?)$")
_EXPOSURE_RX = re.compile(rf"^{EXPOSURE_TAG}(\d+(?:\.\d+)?)$")


# ---------------------------------------------------------------------------------------------- the wanted thing
@dataclass(frozen=True)
class Wanted:
    """What a spec asks for after normalisation (``None``: no constraint)."""

    category: str | None
    subtype: str | None
    color: str | None
    size: tuple[float, float, float] | None

    def describe(self, description: str) -> str:
        parts = [p for p in (self.category, self.subtype and f"subtype {self.subtype}",
                             self.color and f"colour {self.color}",
                             self.size and "size {:.2g} x {:.2g} x {:.2g} m".format(*self.size)) if p]
        return f"{description!r}" + (f" ({', '.join(parts)})" if parts else "")


def _phrases(text: str) -> list[str]:
    """Three-, two- and one-word phrases of ``text`` (lower case), left to right, longest first at each word."""
    words = re.findall(r"[a-z][a-z\-]*", text.lower())
    return [" ".join(words[i:i + n]) for i in range(len(words)) for n in (3, 2, 1) if i + n <= len(words)]


def _noun(word: str) -> tuple[str | None, str | None] | None:
    """``(category, subtype)`` a word names, or ``None`` when it names no object."""
    kind = static_subtype_for(word)
    if kind is not None:
        return "static", kind
    if word in STATIC_GROUPS:
        return "static", word
    if word in NOUNS:
        noun = NOUNS[word][0]
        category = next((c for c in noun.categories if c in ASSET_CATEGORIES), None)
        if category is None and "sign" in noun.categories:
            return "static", noun.subtype or "sign"
        return category or noun.categories[0], noun.subtype  # e.g. "cyclist": a category the bank lacks
    return None


def normalise_color(word: str) -> str:
    """A colour word as a ``COLOR_NAMES`` name (synonyms mapped: grey -> gray, navy -> blue, ...).

    Raises:
        EditRefused: an unknown colour (``reason="no_asset"``, listing the known ones).
    """
    name = COLOR_SYNONYMS.get(word.strip().lower())
    if name is None:
        raise EditRefused(f"unknown colour {word!r}; assets can be {', '.join(COLOR_NAMES)}", reason="no_asset")
    return name


def wanted_from_spec(spec: AssetSpec) -> Wanted:
    """The spec's constraints, filled in from its description where it leaves them out."""
    category: str | None = spec.category
    subtype = spec.subtype
    if subtype is not None:
        named = _noun(subtype.strip().lower())
        subtype = subtype.strip() if named is None else named[1]
        category = category or (named[0] if named else None)
    if category is None or subtype is None:
        for phrase in _phrases(spec.description):
            named = _noun(phrase)
            if named is not None and (category is None or named[0] == category):
                category = category or named[0]
                subtype = subtype or named[1]
                break
    if subtype is not None and category is not None and subtype.lower() in (category, "person", "pedestrian"):
        subtype = None
    color = spec.color
    if color is None:
        color = next((COLOR_SYNONYMS[w] for w in _phrases(spec.description) if w in COLOR_SYNONYMS), None)
    size = None if spec.size_m is None else (float(spec.size_m[0]), float(spec.size_m[1]), float(spec.size_m[2]))
    return Wanted(category, subtype, None if color is None else normalise_color(color), size)


def subtype_fits(wanted: str, have: str) -> bool:
    """Whether an asset of subtype ``have`` is a ``wanted`` (module docstring, point 2)."""
    w, h = wanted.lower(), have.lower()
    if w == h:
        return True
    fit = {k.lower(): v for k, v in SUBTYPE_FIT.get(wanted, SUBTYPE_FIT.get(w, {})).items()}
    if fit.get(h, 0.0) >= 1.0:
        return True
    return have in STATIC_GROUPS.get(w, ())


def _size_fits(have: tuple[float, float, float], wanted: tuple[float, float, float]) -> bool:
    return all(abs(a - b) <= max(SIZE_TOLERANCE * b, SIZE_TOLERANCE_M) for a, b in zip(have, wanted))


def _rebuildable(asset: Asset, wanted: tuple[float, float, float]) -> bool:
    if asset.box_only:
        return True
    kind = STATIC_KINDS.get(asset.attributes.get("procedural", ""))
    if kind is None:
        return False
    ratio = np.asarray(wanted) / np.asarray(kind.size)
    return bool(np.all(ratio >= RESIZE_RANGE[0]) and np.all(ratio <= RESIZE_RANGE[1]))


def _has_color(asset: Asset, color: str) -> bool:
    return asset.color == color or (asset.category == "pedestrian" and asset.attributes.get(LOWER_COLOR) == color)


def clothing_colors(description: str) -> tuple[str | None, str | None]:
    """``(top colour, lower colour)`` a pedestrian's description names ("in a black shirt and blue jeans"),
    as ``COLOR_NAMES`` names (``None``: not named)."""
    query = parse_query(description)
    return (COLOR_SYNONYMS.get(query.upper_color or "", query.upper_color),
            COLOR_SYNONYMS.get(query.lower_color or "", query.lower_color))


def asked_top_color(spec: AssetSpec) -> str | None:
    """The colour a spec asks of a pedestrian's top: its colour unless the description names that colour as the
    lower garment's only ("someone in blue trousers": ``None``); for other categories, the spec's colour."""
    wanted = wanted_from_spec(spec)
    if wanted.color is None or wanted.category != "pedestrian":
        return wanted.color
    upper, lower = clothing_colors(spec.description)
    return None if lower == wanted.color and upper != wanted.color else wanted.color


def _color_pool(assets: Sequence[Asset], typed: list[int], spec: AssetSpec, wanted: Wanted) -> list[int]:
    """The typed assets of the asked colour (point 4). For pedestrians the colour goes in the slot the
    description names (top unless only the lower garment is named in it), and assets matching the other named
    garment's colour too come first. A top asked that no asset wears is made by recolouring (trousers of that
    colour do not make a top of it)."""
    color = wanted.color
    if color is None:
        return typed
    if wanted.category != "pedestrian":
        return [k for k in typed if _has_color(assets[k], color)]
    top = asked_top_color(spec)
    if top is None:  # the trousers' colour only
        return [k for k in typed if assets[k].attributes.get(LOWER_COLOR) == color] or [
            k for k in typed if _has_color(assets[k], color)]
    lower = clothing_colors(spec.description)[1]
    slot = [k for k in typed if assets[k].color == top]
    return [k for k in slot if assets[k].attributes.get(LOWER_COLOR) == lower] or slot


def _canonical(asset: Asset) -> bool:
    kind = STATIC_KINDS.get(asset.attributes.get("procedural", ""))
    return kind is not None and asset.color == kind.colors[0]


def recoloured_caption(asset: Asset, color: str) -> str:
    """The caption ``asset`` gets when recoloured ``color``."""
    if asset.category == "pedestrian":
        return caption_text("pedestrian", asset.subtype, (), color, asset.attributes.get(LOWER_COLOR) or None)
    return caption_text(asset.category, asset.subtype, (color,))


def _quality(asset: Asset, seen_from: Side | None) -> float:
    key = "coverage" if seen_from is None else f"coverage_{seen_from}"
    try:
        return float(asset.attributes.get(key, "1"))
    except ValueError:
        return 1.0


# ---------------------------------------------------------------------------------------------- the bank
def content_hash(assets: Sequence[Asset]) -> str:
    """64 hex digits of SHA-256 over the assets' metadata and tensors (a bank built in memory)."""
    h = hashlib.sha256()
    for a in assets:
        h.update(repr((a.asset_id, a.category, a.subtype, a.caption, a.color, a.size, a.source_seq, a.source_object,
                       sorted(a.attributes.items()))).encode())
        for _, tensor in a.gaussians.named_tensors():
            h.update(tensor.numpy().tobytes())
        for array in (a.deform_frames, a.deform_arc_length):
            if array is not None:
                h.update(array.tobytes())
    return h.hexdigest()


@dataclass(frozen=True, eq=False)
class AssetBank:
    """Assets with unique ids and the hash the bank is stored under (``<root>/assets/<bank_hash>/``).

    Attributes:
        assets: the assets, in a stable order.
        bank_hash: 8-64 lowercase hex digits (the content key of the bank's inputs, or of its contents).
    """

    assets: tuple[Asset, ...]
    bank_hash: str
    _embeddings: dict[str, np.ndarray] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "assets", tuple(self.assets))
        if not _HASH.match(self.bank_hash):
            raise ValueError(f"AssetBank: bank_hash {self.bank_hash!r} must be 8-64 lowercase hex digits")
        ids = Counter(a.asset_id for a in self.assets)
        duplicates = sorted(i for i, n in ids.items() if n > 1)
        if duplicates:
            raise ValueError(f"AssetBank: duplicate asset ids {duplicates}")
        variants = [a.asset_id for a in self.assets if VARIANT_SEP in a.asset_id]
        if variants:
            raise ValueError(f"AssetBank: stored assets cannot be variants ({variants[:3]}); they are derived")

    @classmethod
    def from_assets(cls, assets: Iterable[Asset], bank_hash: str | None = None) -> AssetBank:
        """A bank of ``assets`` (hash: ``bank_hash``, or the hash of their contents)."""
        assets = tuple(assets)
        return cls(assets, bank_hash or content_hash(assets))

    def __len__(self) -> int:
        return len(self.assets)

    @property
    def ids(self) -> list[str]:
        return [a.asset_id for a in self.assets]

    def of_category(self, category: str) -> list[Asset]:
        return [a for a in self.assets if a.category == category]

    # ------------------------------------------------------------------ lookup and variants
    def get(self, asset_id: str) -> Asset:
        """The asset ``asset_id``, or the variant it names: ``<id>~<colour>`` recolours, ``<id>~<l>x<w>x<h>``
        resizes (a procedural asset is rebuilt), ``<id>~exp<gain>`` scales the colours
        (``editing.assets.colors.exposed``); variants chain, in the order of the suffixes.

        Raises:
            EditRefused: no such asset, or a variant that cannot be made (``reason="no_asset"``).
        """
        base, *suffixes = asset_id.split(VARIANT_SEP)
        found = next((a for a in self.assets if a.asset_id == base), None)
        if found is None:
            raise EditRefused(f"no asset {base!r} in bank {self.bank_hash[:12]} ({len(self)} assets)",
                              reason="no_asset")
        asset = found
        for suffix in suffixes:
            size = _SIZE_RX.match(suffix)
            gain = _EXPOSURE_RX.match(suffix)
            try:
                if gain is not None:
                    asset = exposed(asset, float(gain[1]))
                elif size is not None:
                    asset = resized_variant(asset, (float(size[1]), float(size[2]), float(size[3])))
                else:
                    asset = color_variant(asset, suffix)
            except ValueError as exc:
                raise EditRefused(f"cannot make variant {asset_id!r}: {exc}", reason="no_asset") from exc
        return asset

    # ------------------------------------------------------------------ retrieval
    def caption_embeddings(self, encoder: TextEncoder) -> np.ndarray:
        """``[A, D]`` E5 passage embeddings of the captions (cached per encoder name)."""
        cached = self._embeddings.get(encoder.name)
        if cached is None or cached.shape[0] != len(self.assets):
            cached = encoder.encode_passages([a.caption for a in self.assets]) if self.assets else np.zeros((0, 1))
            self._embeddings[encoder.name] = cached
        return cached

    def retrieve(self, spec: AssetSpec, encoder: TextEncoder, *, seen_from: Side | None = None,
                 walking: bool | None = None, exclude: frozenset[str] = frozenset()) -> Asset:
        """The asset that best fits ``spec`` (module docstring), recoloured / rebuilt when needed.

        Args:
            spec: the command's asset.
            encoder: the text encoder (E5) captions and descriptions are compared in.
            seen_from: the side of the object the camera will mostly see (ranks by that side's coverage).
            walking: for pedestrians: prefer sources that walked (``True``) or stood (``False``).
            exclude: stored asset ids not to use while another asset fits the type (and size).

        Raises:
            EditRefused: ``reason="no_asset"``, saying what was asked and what the bank has.
        """
        if spec.asset_id is not None:
            return self.get(spec.asset_id)
        wanted = wanted_from_spec(spec)
        typed = [k for k, a in enumerate(self.assets)
                 if (wanted.category is None or a.category == wanted.category)
                 and (wanted.subtype is None or subtype_fits(wanted.subtype, a.subtype))]
        if wanted.size is not None:
            size = wanted.size
            typed = [k for k in typed if _size_fits(self.assets[k].size, size) or _rebuildable(self.assets[k], size)]
        if not typed:
            raise EditRefused(self._refusal(spec.description, wanted), reason="no_asset")
        typed = [k for k in typed if self.assets[k].asset_id not in exclude] or typed
        exact = _color_pool(self.assets, typed, spec, wanted)
        pool = exact or typed
        recolour = None if exact else wanted.color
        scores = self._scores(spec.description, pool, encoder, seen_from, walking, recolour)
        best = self.assets[pool[int(np.argmax(scores))]]
        asset = best
        if wanted.color is not None and not exact:
            asset = color_variant(asset, wanted.color)
        if wanted.size is not None and (asset.procedural or asset.box_only or not _size_fits(asset.size, wanted.size)):
            if tuple(f32(v) for v in wanted.size) != asset.size:
                asset = resized_variant(asset, wanted.size)
        logger.info("asset for %s: %s", wanted.describe(spec.description), asset.label)
        return asset

    def _scores(self, description: str, pool: list[int], encoder: TextEncoder, seen_from: Side | None,
                walking: bool | None, recolour: str | None) -> np.ndarray:
        """``[P]`` ranking scores of the pool (module docstring, point 5; ties broken by Gaussians and id).
        With ``recolour`` the captions are compared as they will read after recolouring."""
        query = encoder.encode_queries([description])[0]
        if recolour is None:
            sims = self.caption_embeddings(encoder)[pool] @ query
        else:
            sims = encoder.encode_passages([recoloured_caption(self.assets[k], recolour) for k in pool]) @ query
        bonus = np.array([QUALITY_WEIGHT * _quality(self.assets[k], seen_from)
                          + (CANONICAL_BONUS if recolour is None and _canonical(self.assets[k]) else 0.0)
                          for k in pool])
        if walking is not None:
            walked = np.array([self.assets[k].walked_m >= 0.5 for k in pool])
            bonus += WALKING_BONUS * (walked == walking)
        order = sorted(range(len(pool)), key=lambda i: (self.assets[pool[i]].num_gaussians,
                                                        self.assets[pool[i]].asset_id))
        tie = np.empty(len(pool))
        tie[order] = np.arange(len(pool)) * 1e-9  # more Gaussians, then the later id, win exact ties
        return sims + bonus + tie

    def _refusal(self, description: str, wanted: Wanted) -> str:
        """What was asked and what the bank has of that category (or of every category)."""
        categories = [wanted.category] if wanted.category else list(ASSET_CATEGORIES)
        have = []
        for category in categories:
            members = self.of_category(category)
            if not members:
                have.append(f"no {category} assets")
                continue
            kinds: dict[str, set[str]] = {}
            sizes: dict[str, list[tuple[float, float, float]]] = {}
            for a in members:
                kinds.setdefault(a.subtype, set()).add(a.color)
                sizes.setdefault(a.subtype, []).append(a.size)
            listed = []
            for subtype in sorted(kinds):
                dims = np.median(np.asarray(sizes[subtype]), axis=0)
                listed.append(f"{subtype} ({', '.join(sorted(kinds[subtype]))}; ~{dims[0]:.1f} x {dims[1]:.1f} x "
                              f"{dims[2]:.1f} m)")
            have.append(f"{category}: " + "; ".join(listed))
        note = " (other colours are made by recolouring an asset of the right type)" if wanted.color else ""
        listing = " | ".join(have)
        return f"no asset fits {wanted.describe(description)}: the bank ({len(self)} assets) has {listing}{note}"


# ---------------------------------------------------------------------------------------------- variants
def color_variant(asset: Asset, color: str) -> Asset:
    """``asset`` in ``color``: a procedural asset rebuilt, a cut-out recoloured (``editing.assets.colors.recolored``).

    Raises:
        ValueError: unknown colour, or no body to recolour.
    """
    color = COLOR_SYNONYMS.get(color.lower(), color)
    if asset.color == color:
        return asset
    if asset.box_only:  # nothing to paint: the colour and the caption change
        return _box_recolored(asset, color)
    kind = asset.attributes.get("procedural")
    if kind in STATIC_KINDS:
        rebuilt = procedural_asset(kind, color, asset.size, asset_id=f"{asset.asset_id}{VARIANT_SEP}{color}")
        return _with_attributes(rebuilt, {**asset.attributes, RECOLOURED_FROM: asset.asset_id})
    return recolored(asset, color)


def resized_variant(asset: Asset, size: tuple[float, float, float]) -> Asset:
    """``asset`` at box ``size``: a procedural asset rebuilt at that size, a cut-out scaled per axis (means
    and offsets; each Gaussian's scales by the mean factor).

    Raises:
        ValueError: a non-positive size, or a procedural size outside ``RESIZE_RANGE``.
    """
    if min(size) <= 0:
        raise ValueError(f"size must be positive, got {size}")
    tag = "{:.2f}x{:.2f}x{:.2f}".format(*size)
    new_id = f"{asset.asset_id}{VARIANT_SEP}{tag}"
    kind = asset.attributes.get("procedural")
    if kind in STATIC_KINDS:
        rebuilt = procedural_asset(kind, asset.color, size, asset_id=new_id)
        return _with_attributes(rebuilt, {**asset.attributes, RESIZED_FROM: asset.asset_id})
    per_axis = np.asarray(size, dtype=np.float32) / np.asarray(asset.size, dtype=np.float32)
    scale = torch.as_tensor(per_axis)
    log_mean = float(np.log(per_axis).mean())

    def _scaled(name: str, t: torch.Tensor) -> torch.Tensor:
        if name in ("means", "offsets"):
            return t * scale
        return t + log_mean if name == "log_scales" else t

    gs = asset.gaussians.map_rows(_scaled)
    return replace(asset, asset_id=new_id, size=size, gaussians=gs,
                   attributes={**asset.attributes, RESIZED_FROM: asset.asset_id})


def _box_recolored(asset: Asset, color: str) -> Asset:
    if color not in COLOR_NAMES:
        raise ValueError(f"unknown colour {color!r}; known: {list(COLOR_NAMES)}")
    if asset.category == "pedestrian":
        caption = caption_text("pedestrian", asset.subtype, (), color, asset.attributes.get(LOWER_COLOR) or None)
    else:
        caption = caption_text(asset.category, asset.subtype, (color,))
    return replace(asset, asset_id=f"{asset.asset_id}{VARIANT_SEP}{color}", caption=caption, color=color,
                   attributes={**asset.attributes, RECOLOURED_FROM: asset.asset_id})


def _with_attributes(asset: Asset, attributes: dict[str, str]) -> Asset:
    return replace(asset, attributes=attributes)


__all__ = ["Asset", "AssetBank", "QUALITY_WEIGHT", "SIZE_TOLERANCE", "SIZE_TOLERANCE_M", "WALKING_BONUS", "Wanted",
           "asked_top_color", "clothing_colors", "color_variant", "content_hash", "normalise_color",
           "resized_variant", "subtype_fits", "wanted_from_spec"]
