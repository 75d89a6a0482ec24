"""What the commands print: on a pipe or a file (not a terminal) no table or line wraps at 80 columns."""

from __future__ import annotations

from types import SimpleNamespace

from flows.cli import printers

PROMPT = "make the white box truck parked on the right of the road ahead of us pull out and overtake " * 2


def _mined() -> dict:
    scenario = {"seq_id": "synth-000001", "prompt": PROMPT.strip(), "category": "modify_vehicle", "attempts": 2,
                "plausibility": 4, "edit_dir": "/a/long/store/edits/mine-20260101T000000/synth-000001/0123456789abcdef"}
    return {"run_id": "mine-20260101T000000", "edits_table": "/a/long/store/root/edits/mine/edits.parts",
            "scenarios": [scenario], "totals": {"sequences": 1, "attempts": 2, "accepted": 1,
                                                "per_category": {"modify_vehicle": 1}}}


def test_tables_on_a_pipe_do_not_wrap(capsys, monkeypatch):
    monkeypatch.delenv("COLUMNS", raising=False)
    assert printers.console().width == printers.PIPE_WIDTH  # pytest's captured stdout is not a terminal
    printers.print_mining(_mined())
    lines = capsys.readouterr().out.splitlines()
    row = next(line for line in lines if "synth-000001" in line and "modify_vehicle" in line)
    assert PROMPT.strip() in row and row.rstrip().endswith("│") and len(row) > 200
    assert any(line.startswith("1 accepted of 2 attempt(s)") and line.endswith("edits.parts") for line in lines)


def test_columns_set_by_the_user_win(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "100")
    assert printers.console().width == 100
    printers.print_search("a car", SimpleNamespace(hits=[], message="no hit"))
    assert "no hit" in capsys.readouterr().out
