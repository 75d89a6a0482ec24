"""Captions from a vision-language model over the OpenAI-compatible chat API (``AppearanceCaptioner``).

    captioner = VlmCaptioner(OpenAIChatClient(OpenAIChatConfig.from_env()))
    CaptionEmbedder(text_encoder, captioner)       # instead of the built-in rule-based captioner

Each request shows the model the object's crop with everything outside its projected mask greyed
out (so a neighbour in the crop is not described), upscaled so the short side has at least
``min_side`` pixels, and asks for one short noun phrase in the style of the built-in captions ("a red
SUV", "a pedestrian in a white top and black trousers"). ``describe_track`` sends the ``views``
largest crops of an object in one request. The reply is cleaned (first line, no quotes or trailing
full stop, an article in front) and parsed with the query parser, so colours, garment colours and the
subtype land in the same ``AppearanceCaption`` fields the rule-based captioner fills; the category
always comes from the track (the scene graph knows what the object is).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from simsplat_core.language.appearance.captioner import AppearanceCaption, article
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.language.grounding.parse import parse_query
from simsplat_core.vlm.openai_chat import OpenAIChatClient, user_message

logger = logging.getLogger(__name__)

#: What the model is asked for each category (the examples fix the style of the answer).
PROMPTS: dict[str, str] = {
    "vehicle": "Describe the vehicle in the image as one short noun phrase with its colour and type, "
               "like 'a red SUV' or 'a white pickup truck'.",
    "pedestrian": "Describe the person in the image as one short noun phrase with the colours of their top "
                  "and trousers, like 'a pedestrian in a red top and blue trousers'.",
}
DEFAULT_PROMPT = ("Describe the object in the image as one short noun phrase with its colour, "
                  "like 'an orange traffic cone'.")
#: Grey that replaces pixels outside the object's mask.
MASK_GREY = 0.5


def masked_view(crop: ObjectCrop, min_side: int) -> np.ndarray:
    """``[h', w', 3]`` float32: the crop, grey outside its mask, upscaled (nearest) to ``min_side`` pixels."""
    rgb = np.where(crop.mask[..., None], crop.rgb, np.float32(MASK_GREY)).astype(np.float32)
    short = min(rgb.shape[:2])
    if short < min_side:
        scale = int(np.ceil(min_side / max(short, 1)))
        return cv2.resize(rgb, (rgb.shape[1] * scale, rgb.shape[0] * scale), interpolation=cv2.INTER_NEAREST)
    return rgb


def clean_reply(reply: str) -> str:
    """The first line of a model's reply as a caption: no quotes, labels or final full stop; with an article."""
    line = next((ln for ln in reply.strip().splitlines() if ln.strip()), "").strip()
    line = re.sub(r"^(caption|answer|description)\s*:\s*", "", line, flags=re.IGNORECASE)
    line = line.strip(" \t\"'`*").rstrip(".!").strip()
    if not line:
        return ""
    first = line.split()[0].lower()
    if first not in ("a", "an", "the"):
        line = f"{article(line)} {line}"
    elif first == "the":
        rest = line.split(" ", 1)[1] if " " in line else ""
        line = f"{article(rest)} {rest}" if rest else line
    return line[0].lower() + line[1:]


def caption_from_reply(reply: str, category: str) -> AppearanceCaption:
    """An ``AppearanceCaption`` from a model's reply: the cleaned text and the colours / subtype in it.

    Raises:
        ValueError: the reply holds no text.
    """
    text = clean_reply(reply)
    if not text:
        raise ValueError(f"the model's reply {reply!r} holds no caption")
    parsed = parse_query(text)
    subtype = parsed.subtype or ("adult" if category == "pedestrian" else category)  # the built-in captioner's defaults
    upper, lower = (parsed.upper_color, parsed.lower_color) if category == "pedestrian" else (None, None)
    colors = tuple(c for c in (upper, lower) if c) + tuple(c for c in parsed.colors if c not in (upper, lower))
    return AppearanceCaption(text=text, category=category, subtype=subtype, colors=colors, upper_color=upper,
                             lower_color=lower, confidence=0.5)


@dataclass
class VlmCaptioner:
    """``AppearanceCaptioner`` backed by a chat-completion VLM (module docstring).

    Attributes:
        client: the OpenAI-compatible client (endpoint, model, key variable).
        views: crops sent per object by ``describe_track`` (the largest ones).
        min_side: crops are upscaled so their short side has at least this many pixels.
        max_tokens: reply budget.

    Answers are remembered per set of views (object, frame, camera), so asking again for the same crops
    (the scene builder captions tracks and embeds them) costs no second request.
    """

    client: OpenAIChatClient
    views: int = 2
    min_side: int = 64
    max_tokens: int = 32
    _answers: dict[tuple, AppearanceCaption] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        if self.views < 1 or self.min_side < 1 or self.max_tokens < 1:
            raise ValueError(f"VlmCaptioner: views, min_side and max_tokens must be >= 1, got "
                             f"{self.views}, {self.min_side}, {self.max_tokens}")

    @property
    def name(self) -> str:
        return f"vlm-captioner/{self.client.name}"

    def _ask(self, crops: Sequence[ObjectCrop]) -> AppearanceCaption:
        key = tuple((c.object_id, int(c.frame_idx), c.camera, c.bbox) for c in crops)
        if key not in self._answers:
            self._answers[key] = self._request(crops)
        return self._answers[key]

    def _request(self, crops: Sequence[ObjectCrop]) -> AppearanceCaption:
        category = crops[0].category
        prompt = PROMPTS.get(category, DEFAULT_PROMPT)
        if len(crops) > 1:
            prompt = f"The {len(crops)} images show the same object from different views. " + prompt
        reply = self.client.complete([user_message(prompt + " Answer with the phrase only.",
                                                   [masked_view(c, self.min_side) for c in crops])],
                                     max_tokens=self.max_tokens)
        caption = caption_from_reply(reply, category)
        logger.debug("%s: %s", crops[0].object_id, caption.text)
        return caption

    def describe(self, crop: ObjectCrop) -> AppearanceCaption:
        """Caption of one crop (one request)."""
        return self._ask([crop])

    def describe_track(self, crops: Sequence[ObjectCrop]) -> AppearanceCaption:
        """One caption for an object from its ``views`` largest crops (one request).

        Raises:
            ValueError: no crops.
        """
        if not crops:
            raise ValueError("describe_track needs at least one crop")
        largest = sorted(crops, key=lambda c: c.area, reverse=True)[: self.views]
        return self._ask(largest)


__all__ = ["PROMPTS", "VlmCaptioner", "caption_from_reply", "clean_reply", "masked_view"]
