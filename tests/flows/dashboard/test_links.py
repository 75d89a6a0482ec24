"""Dashboard links in the main flow's artifacts: the run page and each mined scenario's card when
``SIMSPLAT_DASHBOARD_URL`` is set, none when it is not."""

from __future__ import annotations

from flows.dashboard.links import run_link, scenario_link
from flows.pipeline import MainResult, _summary_markdown
from tasks.mine import MinedScenario, MiningSummary


def test_links_follow_the_fixed_url_scheme() -> None:
    assert run_link("http://h:8765", "main-1") == "http://h:8765/runs/main-1"
    assert scenario_link("http://h:8765/", "main-1", "synth-000001", "e 1") == \
        "http://h:8765/scenarios/main-1/synth-000001/e%201"
    assert run_link(None, "main-1") is None and scenario_link("", "r", "s", "e") is None


def _mined() -> MainResult:
    scenario = MinedScenario("synth-000001", "edit-abc", "add a cone ahead", "add_static", 1, 8, "/store/edits/x")
    summary = MiningSummary("synth-000001", "main-1", "rule", attempts=2, accepted=1, scenarios=(scenario,))
    return MainResult(logs=[], scenes=[], run_id="main-1", mining=[summary])


def test_the_summary_links_the_run_and_its_scenarios_when_a_dashboard_is_configured(monkeypatch) -> None:
    monkeypatch.setenv("SIMSPLAT_DASHBOARD_URL", "http://127.0.0.1:8765/")
    text = _summary_markdown(_mined())
    assert "[add a cone ahead](http://127.0.0.1:8765/scenarios/main-1/synth-000001/edit-abc)" in text
    assert "(http://127.0.0.1:8765/runs/main-1)" in text
    monkeypatch.delenv("SIMSPLAT_DASHBOARD_URL")
    assert "http" not in _summary_markdown(_mined())


def test_the_mined_scenarios_table_carries_each_cards_link(monkeypatch) -> None:
    import flows.pipeline as pipeline

    published: list = []
    monkeypatch.setattr(pipeline, "create_table_artifact", lambda rows, **kw: published.append(rows))
    monkeypatch.setenv("SIMSPLAT_DASHBOARD_URL", "http://127.0.0.1:8765")
    pipeline._publish_mining_table(_mined().mining, "main-1")
    assert [row["dashboard"] for row in published[0]] == ["http://127.0.0.1:8765/scenarios/main-1/synth-000001/edit-abc"]
