"""The registry of driving-log sources: name -> loader, what it reads, and how a file or folder of it is recognised.

``simsplat ingest SOURCE PATH`` goes through it, and ``find_logs`` finds every log under a folder. A new dataset is
one loader module (a ``load_...(path, seq_id=None, ...) -> SceneLog`` and an ``is_...(path) -> bool``) plus one
line in ``LOG_SOURCES``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from simsplat_core.data.av2 import is_av2_sensor_log, load_av2_log
from simsplat_core.data.av2_forecasting import is_av2_forecasting_scenario, load_av2_forecasting
from simsplat_core.data.waymo import is_waymo_frame_file, load_waymo_frames
from simsplat_core.data.waymo_scenario import is_waymo_scenario_file, load_waymo_scenario
from simsplat_core.types import SceneLog

#: The ``SOURCE`` that asks for detection instead of naming a source.
AUTO_SOURCE = "auto"


class UnknownLogSourceError(ValueError):
    """A source name that is not in the registry, or a path that no source recognises; the message lists the
    known sources."""


@dataclass(frozen=True)
class LogSource:
    """One kind of driving log.

    Attributes:
        name: the ``SOURCE`` of ``simsplat ingest`` (also ``SceneLog.source`` of the logs it loads).
        description: one line: what a log of this source is and what the loader keeps.
        detect: whether a path is a log of this source (cheap, never raises).
        load: ``load(path, seq_id=None, **options) -> SceneLog``; raises ``CorruptLogError`` for bad input.
        options: the keyword options ``load`` takes besides ``seq_id`` (e.g. ``"image_scale"``).
    """

    name: str
    description: str
    detect: Callable[[Path], bool]
    load: Callable[..., SceneLog]
    options: tuple[str, ...] = ()


LOG_SOURCES: tuple[LogSource, ...] = (
    LogSource("waymo-frame", "Waymo Open Dataset Frame TFRecord (one segment): cameras, laser labels, poses",
              is_waymo_frame_file, load_waymo_frames, ("image_scale",)),
    LogSource("waymo-scenario", "Waymo Open Motion Scenario TFRecord: tracks, ego, lanes, edges, crosswalks, "
              "signals; no images", is_waymo_scenario_file, load_waymo_scenario),
    LogSource("av2", "Argoverse 2 sensor log directory: annotations, poses, calibration, vector map; no images",
              is_av2_sensor_log, load_av2_log),
    LogSource("av2-forecasting", "Argoverse 2 motion-forecasting scenario (directory or scenario_*.parquet): "
              "10 Hz tracks, focal / scored tracks, vector map; no images", is_av2_forecasting_scenario,
              load_av2_forecasting),
)


def source_names() -> tuple[str, ...]:
    """The registered source names, in registry order."""
    return tuple(source.name for source in LOG_SOURCES)


def known_sources_text() -> str:
    """The registered sources, one ``name: description`` per line (for error messages and help)."""
    return "\n".join(f"  {source.name}: {source.description}" for source in LOG_SOURCES)


def log_source(name: str) -> LogSource:
    """The registered source ``name``.

    Raises:
        UnknownLogSourceError: no such source (the message lists the known ones).
    """
    for source in LOG_SOURCES:
        if source.name == name:
            return source
    raise UnknownLogSourceError(f"unknown log source {name!r}; known sources:\n{known_sources_text()}")


def detect_source(path: str | Path) -> str | None:
    """The name of the source whose ``detect`` accepts ``path``, or ``None`` when none does.

    Raises:
        UnknownLogSourceError: several sources claim ``path`` (a registry bug: detections must exclude each
            other).
    """
    path = Path(path)
    found = [source.name for source in LOG_SOURCES if source.detect(path)]
    if len(found) > 1:
        raise UnknownLogSourceError(f"{path}: several log sources recognise it: {found}")
    return found[0] if found else None


def resolve_source(source: str, path: str | Path) -> LogSource:
    """``source`` from the registry, or for ``AUTO_SOURCE`` the source detected for ``path``.

    Raises:
        UnknownLogSourceError: an unknown name, or ``auto`` and no source recognises ``path`` (both list the
            known sources).
    """
    if source != AUTO_SOURCE:
        return log_source(source)
    detected = detect_source(path)
    if detected is None:
        raise UnknownLogSourceError(f"{path}: no log source recognises it; known sources:\n{known_sources_text()}")
    return log_source(detected)


def load_log(source: str, path: str | Path, seq_id: str | None = None, **options: Any) -> SceneLog:
    """Load ``path`` with the loader of ``source`` (``AUTO_SOURCE``: detected).

    Args:
        options: loader options; each must be one of the source's ``options``.

    Raises:
        UnknownLogSourceError: see ``resolve_source``.
        TypeError: an option the source does not take (named, with the ones it takes).
        CorruptLogError, FileNotFoundError: the loader's errors.
    """
    chosen = resolve_source(source, path)
    extra = sorted(set(options) - set(chosen.options))
    if extra:
        raise TypeError(f"log source {chosen.name!r} takes no option {extra[0]!r} "
                        f"(its options: {list(chosen.options) or 'none'})")
    return chosen.load(Path(path), seq_id=seq_id, **options)


def find_logs(folder: str | Path) -> Iterator[tuple[str, Path]]:
    """``(source name, path)`` of every log under ``folder`` (a landing folder), in sorted path order.

    A path that a source recognises is a log and is not searched further; other directories are searched
    recursively; hidden entries (``.name``) are skipped.
    """
    folder = Path(folder)
    source = detect_source(folder)
    if source is not None:
        yield source, folder
        return
    if folder.is_dir():
        for child in sorted(folder.iterdir()):
            if not child.name.startswith("."):
                yield from find_logs(child)
