"""EXR renders through OpenImageIO (``DESIGN.md``: float32, zip compression).

Channels, in canonical order: ``R, G, B, A`` (colour, alpha), ``Z`` (metric z-depth, ``inf`` where
nothing was hit), ``id`` (instance / node id), ``feat.00 .. feat.NN`` (language features). Every
channel is a ``[H, W]`` float32 image stored as 32-bit float with lossless zip compression by default,
so a round trip is bit-exact, ``inf`` and ``nan`` included.

``write_exr(..., half=True)`` stores every channel but ``id`` as 16-bit HALF (relative error <= 2**-11,
about 0.0005 on colours in ``[0, 1]``; values above 65504 become ``inf``): half the bytes for previews
and edit renders that thousands of mined edits write. ``id`` stays float32 in every case: integer ids
are exact up to ``2**24`` (16,777,216); larger ids are rejected rather than silently rounded.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping

import numpy as np
import OpenImageIO as oiio

from storage.errors import CorruptArtifactError
from storage.store import ArtifactStore

logger = logging.getLogger(__name__)

BASE_CHANNELS: tuple[str, ...] = ("R", "G", "B", "A", "Z", "id", "mask")
#: The per-pixel validity channel (1 = valid, 0 = invalid; ``CameraImage.valid_mask``).
MASK_CHANNEL = "mask"
#: The node / instance id channel (always float32: exact integers).
ID_CHANNEL = "id"
FEATURE_PREFIX = "feat."
COMPRESSION = "zip"
#: Largest integer id that float32 represents exactly (and every smaller one).
MAX_EXACT_ID = 2**24
_FEATURE_RE = re.compile(r"^feat\.(\d{2,})$")


def feature_channel(index: int) -> str:
    """Name of feature channel ``index``: ``feat.00``, ``feat.01``, ..., ``feat.100``."""
    return f"{FEATURE_PREFIX}{index:02d}"


def _sort_key(name: str) -> tuple[int, int]:
    if name in BASE_CHANNELS:
        return (0, BASE_CHANNELS.index(name))
    match = _FEATURE_RE.match(name)
    if match:
        return (1, int(match.group(1)))
    return (2, 0)


def canonical_order(names: list[str] | tuple[str, ...]) -> list[str]:
    """``names`` sorted as R, G, B, A, Z, id, feat.NN by number; unknown names keep their order at the end."""
    return sorted(names, key=_sort_key)  # sorted() is stable


def render_channels(
    rgb: np.ndarray | None = None,
    alpha: np.ndarray | None = None,
    depth: np.ndarray | None = None,
    node_id: np.ndarray | None = None,
    features: np.ndarray | None = None,
    valid_mask: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Channel dict for ``write_exr`` from render outputs.

    Args:
        rgb: ``[H, W, 3]`` colour.
        alpha: ``[H, W]`` (or ``[H, W, 1]``) accumulated opacity.
        depth: ``[H, W]`` (or ``[H, W, 1]``) z-depth.
        node_id: ``[H, W]`` integer ids (0 = background), ``|id| <= 2**24``.
        features: ``[H, W, D]`` per-pixel features -> ``feat.00 .. feat.{D-1}``.
        valid_mask: ``[H, W]`` bool validity -> ``mask`` (1.0 valid, 0.0 invalid).

    Returns:
        ``{name: [H, W] float32}`` in canonical order.
    """
    channels: dict[str, np.ndarray] = {}
    if rgb is not None:
        rgb = np.asarray(rgb)
        if rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"rgb must be [H, W, 3], got {rgb.shape}")
        for i, name in enumerate("RGB"):
            channels[name] = rgb[..., i]
    if valid_mask is not None:
        channels[MASK_CHANNEL] = np.asarray(valid_mask).astype(np.float32)
    for name, plane in (("A", alpha), ("Z", depth), ("id", node_id)):
        if plane is not None:
            plane = np.asarray(plane)
            channels[name] = plane[..., 0] if plane.ndim == 3 and plane.shape[2] == 1 else plane
    if features is not None:
        features = np.asarray(features)
        if features.ndim != 3:
            raise ValueError(f"features must be [H, W, D], got {features.shape}")
        for i in range(features.shape[2]):
            channels[feature_channel(i)] = features[..., i]
    return {name: _as_float32(name, channels[name]) for name in canonical_order(list(channels))}


def _as_float32(name: str, plane: np.ndarray) -> np.ndarray:
    plane = np.asarray(plane)
    if plane.ndim != 2:
        raise ValueError(f"EXR channel {name!r} must be [H, W], got shape {plane.shape}")
    if np.issubdtype(plane.dtype, np.integer) and plane.size and int(np.abs(plane).max()) > MAX_EXACT_ID:
        raise ValueError(f"EXR channel {name!r}: integer values above 2**24 are not exact in float32")
    return plane.astype(np.float32, copy=False)


def write_exr(store: ArtifactStore, relpath: str, channels: Mapping[str, np.ndarray], *, half: bool = False) -> None:
    """Write ``{name: [H, W]}`` channels as one zip-compressed EXR, atomically.

    Channel names must be among ``R, G, B, A, Z, id, feat.NN``; they are written in canonical order.
    ``half``: store every channel but ``id`` as 16-bit HALF (module docstring); default float32.

    Raises:
        ValueError: unknown channel name, mismatched shapes, no channels, or ids above ``2**24``.
        OSError: OpenImageIO failed to write (message names the file).
    """
    uri = store.uri(relpath)
    if not channels:
        raise ValueError(f"{uri}: no channels to write")
    unknown = [n for n in channels if _sort_key(n)[0] == 2]
    if unknown:
        raise ValueError(f"{uri}: unknown EXR channel(s) {unknown}; allowed {BASE_CHANNELS} and 'feat.NN'")
    names = canonical_order(list(channels))
    planes = [_as_float32(n, channels[n]) for n in names]
    shapes = {p.shape for p in planes}
    if len(shapes) != 1:
        raise ValueError(f"{uri}: channels differ in shape: {dict(zip(names, (p.shape for p in planes)))}")
    pixels = np.ascontiguousarray(np.stack(planes, axis=-1))  # [H, W, C]
    height, width, _ = pixels.shape
    spec = oiio.ImageSpec(width, height, len(names), oiio.FLOAT)
    spec.channelnames = tuple(names)
    if half:
        spec.channelformats = tuple(oiio.TypeDesc("float" if n == ID_CHANNEL else "half") for n in names)
    spec.alpha_channel = names.index("A") if "A" in names else -1
    spec.z_channel = names.index("Z") if "Z" in names else -1
    spec.attribute("compression", COMPRESSION)
    with store.local_path_for_write(relpath) as path:
        out = oiio.ImageOutput.create("openexr")
        if out is None:
            raise OSError(f"{uri}: OpenImageIO has no EXR writer ({oiio.geterror()})")
        ok = out.open(path, spec) and out.write_image(pixels)
        error = out.geterror()
        out.close()
        if not ok:
            raise OSError(f"{uri}: OpenImageIO could not write EXR ({error})")
    logger.debug("wrote EXR %s [%d x %d] %s%s", uri, height, width, names, " (half)" if half else "")


def _open(path: str, uri: str) -> oiio.ImageInput:
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise CorruptArtifactError(f"{uri}: not a readable EXR file ({oiio.geterror()})")
    return inp


def read_exr(store: ArtifactStore, relpath: str) -> dict[str, np.ndarray]:
    """Read every channel of an EXR as ``{name: [H, W] float32}``, in canonical order.

    Raises:
        FileNotFoundError, CorruptArtifactError: naming the file.
    """
    uri = store.uri(relpath)
    with store.local_path_for_read(relpath) as path:
        inp = _open(path, uri)
        try:
            spec = inp.spec()
            names = list(spec.channelnames)
            pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
            error = inp.geterror()
        finally:
            inp.close()
    if pixels is None or not hasattr(pixels, "shape"):
        raise CorruptArtifactError(f"{uri}: could not decode EXR pixels ({error})")
    pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return {name: np.ascontiguousarray(pixels[..., names.index(name)]) for name in canonical_order(names)}


def read_exr_header(store: ArtifactStore, relpath: str) -> dict[str, object]:
    """Header facts of an EXR: ``width``, ``height``, ``channels``, ``compression``, ``format``."""
    uri = store.uri(relpath)
    with store.local_path_for_read(relpath) as path:
        inp = _open(path, uri)
        try:
            spec = inp.spec()
            formats = spec.channelformats or (spec.format,) * spec.nchannels
            return {
                "width": spec.width,
                "height": spec.height,
                "channels": list(spec.channelnames),
                "compression": spec.get_string_attribute("compression"),
                "format": sorted({str(f) for f in formats}),
            }
        finally:
            inp.close()
