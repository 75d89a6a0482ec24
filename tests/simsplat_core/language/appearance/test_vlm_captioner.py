"""VlmCaptioner: reply parsing, and captioning through a real OpenAI-compatible server on 127.0.0.1."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from simsplat_core.language.appearance.captioner import AppearanceCaptioner
from simsplat_core.language.appearance.embedders import CaptionEmbedder
from simsplat_core.language.appearance.vlm_captioner import (
    MASK_GREY,
    VlmCaptioner,
    caption_from_reply,
    clean_reply,
    masked_view,
)
from simsplat_core.vlm import OpenAIChatClient, OpenAIChatConfig
from tests.simsplat_core.language.appearance.helpers import PAINTS, HashTextEncoder, make_crop, paint_vehicle
from tests.simsplat_core.vlm.chat_server import ChatServer, images_of

SUV = (4.85, 1.95, 1.78)
GREY = round(MASK_GREY * 255)


def _stand_in_vlm(body) -> tuple[int, dict]:
    """Names the colour of the non-grey pixels it is shown: red -> "A red SUV.", else "a black sedan"."""
    pixels = np.concatenate([img.reshape(-1, 3) for img in images_of(body)]).astype(int)
    shown = pixels[np.abs(pixels - GREY).max(axis=1) > 2]
    reddish = shown.size and shown[:, 0].mean() > 2 * shown[:, 1].mean() + 20
    text = '"A red SUV."' if reddish else "a black sedan"
    return 200, {"choices": [{"message": {"role": "assistant", "content": text}}]}


@pytest.fixture()
def server() -> Iterator[ChatServer]:
    srv = ChatServer(reply=_stand_in_vlm).start()
    yield srv
    srv.stop()


def _captioner(server: ChatServer, **kw) -> VlmCaptioner:
    return VlmCaptioner(OpenAIChatClient(OpenAIChatConfig(base_url=server.base_url, model="stand-in", backoff_s=0)),
                        **kw)


def _crops(oid: str, paint: str, sizes=((40, 90), (24, 54), (16, 36))):
    out = []
    for frame, (h, w) in enumerate(sizes):
        rgb, mask = paint_vehicle(PAINTS[paint], height=h, width=w, seed=frame)
        out.append(make_crop(rgb, mask, "vehicle", SUV, oid, frame))
    return out


@pytest.mark.parametrize(("reply", "text"), [
    ('"A red SUV."', "a red SUV"),
    ("Caption: white van", "a white van"),
    ("The green hatchback\nIt is parked.", "a green hatchback"),
    ("  **an orange traffic cone**  ", "an orange traffic cone"),
    ("   ", ""),
])
def test_clean_reply(reply: str, text: str) -> None:
    assert clean_reply(reply) == text


def test_caption_from_reply_fills_the_captioners_fields() -> None:
    car = caption_from_reply("A dark grey SUV.", "vehicle")
    assert (car.text, car.subtype, car.colors, car.upper_color) == ("a dark grey SUV", "SUV", ("gray",), None)
    person = caption_from_reply("a pedestrian in a red shirt and blue jeans", "pedestrian")
    assert (person.upper_color, person.lower_color, person.colors, person.subtype) == (
        "red", "blue", ("red", "blue"), "adult"
    )
    assert caption_from_reply("a small child in a yellow top", "pedestrian").subtype == "child"
    with pytest.raises(ValueError, match="no caption"):
        caption_from_reply("''", "vehicle")


def test_masked_view_greys_out_the_background_and_upscales() -> None:
    crop = _crops("suv", "red", sizes=((16, 36),))[0]
    view = masked_view(crop, min_side=64)
    assert min(view.shape[:2]) >= 64 and view.shape[0] % crop.rgb.shape[0] == 0
    scale = view.shape[0] // crop.rgb.shape[0]
    np.testing.assert_allclose(view[::scale, ::scale][~crop.mask], MASK_GREY)
    np.testing.assert_allclose(view[::scale, ::scale][crop.mask], crop.rgb[crop.mask])


def test_track_caption_asks_once_with_the_largest_views(server: ChatServer) -> None:
    captioner = _captioner(server, views=2)
    assert isinstance(captioner, AppearanceCaptioner) and "stand-in" in captioner.name
    crops = _crops("suv", "red")
    caption = captioner.describe_track(crops[::-1])
    assert (caption.text, caption.colors, caption.subtype, caption.category) == (
        "a red SUV", ("red",), "SUV", "vehicle"
    )
    (request,) = server.requests
    images = images_of(request["body"])
    assert len(images) == 2 and images[0].shape[0] > images[1].shape[0]  # the two largest, largest first
    assert "same object" in request["body"]["messages"][0]["content"][0]["text"]
    assert captioner.describe_track(crops[::-1]) == caption and len(server.requests) == 1  # remembered
    assert captioner.describe(crops[2]).text == "a red SUV" and len(server.requests) == 2


def test_caption_embedder_per_object_sends_one_request_per_object(server: ChatServer) -> None:
    captioner = _captioner(server)
    embedder = CaptionEmbedder(HashTextEncoder(), captioner, per_view=False)
    crops = _crops("suv", "red") + _crops("sedan", "black")
    feats = embedder.embed(crops)
    assert len(server.requests) == 2
    np.testing.assert_allclose(feats[0], feats[2])
    assert float(feats[0] @ feats[3]) < 0.99
    texts = [c.text for c in embedder.captions(crops)]
    assert texts == ["a red SUV"] * 3 + ["a black sedan"] * 3 and len(server.requests) == 2
    assert "per-object" in embedder.name and "stand-in" in embedder.name


def test_appearance_embedder_by_name(server: ChatServer, monkeypatch) -> None:
    from simsplat_core.language.alignment.scene_builder import AlignmentConfig, AlignmentConfigError
    from simsplat_core.language.appearance.embedders import appearance_embedder
    from simsplat_core.vlm import VLMError

    encoder = HashTextEncoder()
    assert appearance_embedder("builtin", encoder).per_view
    monkeypatch.delenv("SIMSPLAT_VLM_URL", raising=False)
    with pytest.raises(VLMError, match="SIMSPLAT_VLM_URL"):
        appearance_embedder("vlm", encoder)
    monkeypatch.setenv("SIMSPLAT_VLM_URL", server.base_url)
    monkeypatch.setenv("SIMSPLAT_VLM_MODEL", "stand-in")
    vlm = appearance_embedder("vlm", encoder)
    assert not vlm.per_view and isinstance(vlm.captioner, VlmCaptioner)
    assert vlm.captions(_crops("suv", "red")[:1])[0].text == "a red SUV"
    with pytest.raises(ValueError, match="unknown captioner 'clip'"):
        appearance_embedder("clip", encoder)
    with pytest.raises(AlignmentConfigError, match="AlignmentConfig.captioner"):
        AlignmentConfig(captioner="clip").validate()
