"""``storage.inventory``: what the store holds per sequence, and the one error that names what is missing and the
command that makes it."""

from __future__ import annotations

import pytest

from storage import ArtifactStore, mark_done
from storage.errors import MissingInputError
from storage.inventory import LANGUAGE_SCENE, SCENE, require_asset_bank, require_sequences, sequences_with

SCENE_HASH = "5ce4e" + "0" * 59
LANGUAGE_HASH = "1a900" + "0" * 59
BANK_HASH = "ba4c0" + "0" * 59


def _log(store: ArtifactStore, seq_id: str) -> None:
    mark_done(store, f"logs/{seq_id}", f"log-{seq_id}")


def test_an_empty_store_says_how_to_add_logs(store: ArtifactStore) -> None:
    with pytest.raises(MissingInputError) as error:
        require_sequences(store)
    text = str(error.value)
    assert "no driving log" in text and "--sequences" in text and "simsplat ingest" in text
    assert isinstance(error.value, FileNotFoundError) and isinstance(error.value, ValueError)
    with pytest.raises(MissingInputError, match=r"no complete log \['nope'\]"):  # a named one is named
        require_sequences(store, ["nope"])
    assert not store.exists("logs")  # checking writes nothing


def test_logs_are_every_complete_one_or_the_chosen_ones(store: ArtifactStore) -> None:
    _log(store, "s1")
    _log(store, "s2")
    store.write_json("logs/s3/frames.json", {})  # no marker: incomplete
    assert require_sequences(store) == ["s1", "s2"] and require_sequences(store, ["s2"]) == ["s2"]
    with pytest.raises(MissingInputError, match=r"no complete log \['s3'\] in .*logs; available: \['s1', 's2'\]"):
        require_sequences(store, ["s2", "s3"])


def test_scenes_name_the_ones_without_and_the_command(store: ArtifactStore) -> None:
    _log(store, "s1")
    _log(store, "s2")
    mark_done(store, f"scenes/s1/{SCENE_HASH}", SCENE_HASH)
    mark_done(store, f"scenes/gone/{SCENE_HASH}", SCENE_HASH)  # a scene without its log does not count
    assert sequences_with(store, SCENE) == ["s1"] and require_sequences(store, None, SCENE) == ["s1"]
    with pytest.raises(MissingInputError) as error:
        require_sequences(store, ["s2", "gone"], SCENE)
    text = str(error.value)
    assert "no reconstructed scene of ['s2', 'gone']" in text and "reconstructed: ['s1']" in text
    assert f"simsplat reconstruct --store {store.root}" in text


def test_language_scenes_name_the_alignment_commands(store: ArtifactStore) -> None:
    _log(store, "s1")
    with pytest.raises(MissingInputError) as error:
        require_sequences(store, None, LANGUAGE_SCENE)
    text = str(error.value)
    assert "no language scene of any log" in text and "aligned: []" in text
    assert "simsplat run" in text and "simsplat align" in text
    mark_done(store, f"alignment/m1/scenes/s1/{LANGUAGE_HASH}", LANGUAGE_HASH)
    assert require_sequences(store, None, LANGUAGE_SCENE) == ["s1"] == sequences_with(store, LANGUAGE_SCENE)


def test_the_asset_bank_is_the_newest_or_an_error_naming_the_build(store: ArtifactStore) -> None:
    with pytest.raises(MissingInputError) as error:
        require_asset_bank(store, "to mine 's1' with")
    text = str(error.value)
    assert "no asset bank to mine 's1' with" in text and f"simsplat assets build --store {store.root}" in text
    mark_done(store, f"assets/{BANK_HASH}", BANK_HASH, {"written_at": "2026-01-01T00:00:00"})
    assert require_asset_bank(store) == BANK_HASH
