"""Real traffic against its log: the reactive predictor's rows of a ``simsplat eval motion`` run, with the targets.

    .venv/bin/simsplat eval motion --out RUN --predictor reactive --no-real-edits --diagnose
    .venv/bin/python bench/motion_real_summary.py RUN [--out bench/results/motion_real.json]

Reads ``RUN/tables/motion.parquet`` (and ``motion_stalls.parquet`` when present) and writes, per real dataset, the
log's row, the reactive rollout's row and whether each target holds: progress at least 0.9 of the log, stopped share
within 2 points of the log's, agents colliding / off-road no more than in the log. Logs the comparison table.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
from run_info import machine_info, write_json_result

logger = logging.getLogger("bench.motion_real_summary")

COLUMNS = ("scenarios", "progress", "stopped_share", "ade_3s", "ade_8s", "agent_collision", "agent_offroad")
COMMAND = "simsplat eval motion --out OUT --predictor reactive --no-real-edits --diagnose (window stride 10)"


def _targets(log: dict[str, Any], rollout: dict[str, Any]) -> dict[str, bool]:
    """Each target of the rollout against its log."""
    return {
        "progress>=0.9": rollout["progress"] >= 0.9,
        "stopped_within_0.02": abs(rollout["stopped_share"] - log["stopped_share"]) <= 0.02 + 1e-9,
        "agent_collision<=log": rollout["agent_collision"] <= log["agent_collision"] + 1e-9,
        "agent_offroad<=log": rollout["agent_offroad"] <= log["agent_offroad"] + 1e-9,
    }


def summarise(run: Path) -> dict[str, Any]:
    """The summary of run directory ``run`` (module docstring)."""
    table = run / "tables" / "motion.parquet"
    if not table.exists():
        raise FileNotFoundError(f"{table}: not a `simsplat eval motion` run directory")
    rows = pq.read_table(table).to_pylist()
    cases: dict[str, dict[str, Any]] = {}
    for row in rows:
        name = "log" if row["method"] == "log" else row["predictor"]
        if name in ("log", "reactive"):
            cases.setdefault(row["dataset"], {})[name] = {k: row[k] for k in COLUMNS}
    for dataset, case in cases.items():
        if {"log", "reactive"} <= set(case):
            case["targets"] = _targets(case["log"], case["reactive"])
        else:
            logger.warning("%s: no reactive row next to the log's", dataset)
    stalls_path = run / "tables" / "motion_stalls.parquet"
    stalls = pq.read_table(stalls_path).num_rows if stalls_path.exists() else None
    return {"command": COMMAND, "window_stride": 10, "cases": cases, "stalls": stalls}


def _fmt(value: float | None) -> str:
    return "" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.3f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="run directory of `simsplat eval motion`")
    parser.add_argument("--out", type=Path, default=Path("bench/results/motion_real.json"))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    summary = summarise(args.run)
    write_json_result(summary | {"machine": machine_info()}, args.out)
    logger.info("%-16s %-9s %9s %17s %17s %17s %7s", "dataset", "progress", "scenarios", "stopped log/now",
                "colliding log/now", "off-road log/now", "ADE 8s")
    for dataset, case in summary["cases"].items():
        log, now = case["log"], case.get("reactive")
        if now is None:
            continue
        logger.info("%-16s %-9s %9d %8s/%-8s %8s/%-8s %8s/%-8s %7s", dataset, _fmt(now["progress"]), now["scenarios"],
                    _fmt(log["stopped_share"]), _fmt(now["stopped_share"]), _fmt(log["agent_collision"]),
                    _fmt(now["agent_collision"]), _fmt(log["agent_offroad"]), _fmt(now["agent_offroad"]),
                    _fmt(now["ade_8s"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
