"""The named colours: one table of colour words and their display RGB, shared by the synthetic world
(which paints with them), the captioner (which names pixels with them) and the query parser (which reads
them). Framework-free and dependency-free so every layer can import it.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class NamedColor:
    """One entry of the naming palette: a name and a representative display RGB in ``[0, 1]``."""

    name: str
    rgb: tuple[float, float, float]


#: Chromatic reference colours; a chromatic region takes the name whose chromaticity
#: ``(a, b) / (L + 16)`` is nearest.
CHROMATIC_PALETTE: tuple[NamedColor, ...] = (
    NamedColor("red", (0.75, 0.07, 0.07)),
    NamedColor("orange", (0.95, 0.42, 0.05)),
    NamedColor("yellow", (0.95, 0.78, 0.08)),
    NamedColor("green", (0.08, 0.45, 0.18)),
    NamedColor("blue", (0.1, 0.22, 0.68)),
    NamedColor("brown", (0.42, 0.26, 0.13)),
    NamedColor("beige", (0.78, 0.7, 0.53)),
    NamedColor("purple", (0.45, 0.2, 0.6)),
    NamedColor("pink", (0.95, 0.55, 0.7)),
)
#: Representative display colours of the achromatic names (the synthetic world paints with them).
ACHROMATIC_PALETTE: tuple[NamedColor, ...] = (
    NamedColor("black", (0.05, 0.05, 0.06)),
    NamedColor("gray", (0.4, 0.41, 0.43)),
    NamedColor("silver", (0.66, 0.68, 0.71)),
    NamedColor("white", (0.9, 0.9, 0.88)),
)
ACHROMATIC_NAMES: tuple[str, ...] = tuple(c.name for c in ACHROMATIC_PALETTE)
COLOR_NAMES: tuple[str, ...] = ACHROMATIC_NAMES + tuple(c.name for c in CHROMATIC_PALETTE)
#: The one table of colour name -> display RGB in ``[0, 1]`` (``world/palette.py`` paints with it).
DISPLAY_RGB: dict[str, tuple[float, float, float]] = {c.name: c.rgb for c in ACHROMATIC_PALETTE + CHROMATIC_PALETTE}
