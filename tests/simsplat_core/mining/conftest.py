"""Fixtures of the mining tests: the editing tests' small synthetic scene (log, untrained graph, ground-truth
language, grounding engine, a three-asset bank) as one ``EditContext``, and its scene facts."""

from __future__ import annotations

import pytest

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.draft import EditContext
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.mining.scene_fact_records import SceneFacts
from simsplat_core.mining.scene_facts import scene_facts
from simsplat_core.scene import SceneGraph
from simsplat_core.types import SceneLog
from tests.simsplat_core.editing.conftest import edit_graph, edit_language, edit_log, encoder, engine  # noqa: F401
from tests.simsplat_core.editing.test_apply import bank  # noqa: F401


@pytest.fixture(scope="module")
def ctx(edit_log: SceneLog, edit_graph: SceneGraph, edit_language: LanguageScene, engine: QueryEngine,  # noqa: F811
        bank: AssetBank) -> EditContext:  # noqa: F811
    return EditContext.create(edit_log, edit_graph, edit_language, engine, bank)


@pytest.fixture(scope="module")
def facts(ctx: EditContext) -> SceneFacts:
    return scene_facts(ctx)
