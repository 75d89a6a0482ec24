"""Benchmark: ``ReactivePredictor.rollout`` time against the number of agents, single-threaded.

    .venv/bin/python bench/bench_motion.py [--agents 10 25 50 100 200] [--repeats 3]

Synthetic scene: a straight four-lane road (3.5 m lanes, one direction) with crosswalks every 150 m; vehicles
spread over the lanes at 6-16 m/s with a logged speed change each (some faster cars close on slower ones,
so the model has leaders to follow and lane changes to consider), one pedestrian in ten crossing the road,
the ego fixed. 11 history steps + 80 future steps at 10 Hz. Reports the median of ``--repeats`` rollouts (the
first warms caches), the number of driven / refined / replayed agents and of free agents colliding with
anyone over the future steps, replaying the log and in the rollout; writes ``bench/results/motion.json``.
Target: <= 1 s for 100 agents x 80 steps.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse
import json
import logging
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from simsplat_core.motion.predictor import MotionMap, RolloutRequest
from simsplat_core.motion.reactive import ReactivePredictor
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import collision_steps
from simsplat_core.types import MapFeature

HISTORY, FUTURE, DT = 11, 80, 0.1
LANES, LANE_W, ROAD_LEN = 4, 3.5, 3000.0
CAR, PERSON = (4.5, 2.0, 1.5), (0.6, 0.6, 1.8)
RESULTS = Path(__file__).parent / "results" / "motion.json"


def _rect(kind: str, fid: str, x0: float, x1: float, y0: float, y1: float) -> MapFeature:
    return MapFeature(fid, kind, np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]]))


def road() -> MotionMap:
    """Four eastbound lanes, a drivable area, a crosswalk every 150 m."""
    feats = []
    for k in range(LANES):
        xs = np.linspace(-100.0, ROAD_LEN, 200)
        feats.append(MapFeature(f"lane{k}", "lane", np.stack([xs, np.full_like(xs, k * LANE_W), 0 * xs], 1)))
    feats.append(_rect("drivable_area", "road", -100.0, ROAD_LEN, -LANE_W / 2, (LANES - 0.5) * LANE_W))
    feats += [_rect("crosswalk", f"cw{k}", x - 2.0, x + 2.0, -LANE_W / 2, (LANES - 0.5) * LANE_W)
              for k, x in enumerate(np.arange(100.0, ROAD_LEN, 150.0))]
    return MotionMap(LaneGraph.from_features(feats), MapContext.from_features(feats))


def scene(n_agents: int, seed: int = 0) -> AgentStates:
    """``n_agents`` agents (the ego first) on the road (see the module docstring)."""
    rng = np.random.default_rng(seed)
    t_count = HISTORY + FUTURE
    times = np.arange(t_count) * DT
    xy = np.zeros((n_agents, t_count, 2))
    heading = np.zeros((n_agents, t_count))
    speed = np.zeros((n_agents, t_count))
    cats, sizes = [], []
    spacing = 25.0  # metres of lane per vehicle
    for a in range(n_agents):
        if a % 10 == 9:  # a pedestrian crossing at a crosswalk, side by side with the others there
            k = a // 10
            n_cw = max(1, int(n_agents * spacing / LANES / 150.0))
            x = 100.0 + 150.0 * (k % n_cw) + 1.2 * ((k // n_cw) % 3 - 1)
            v = rng.uniform(1.0, 1.6)
            y = -4.0 - 1.5 * ((k // n_cw) // 3) + v * (times - rng.uniform(0.0, 4.0))
            xy[a] = np.stack([np.full(t_count, x), y], 1)
            heading[a], speed[a] = np.pi / 2, v
            cats.append("pedestrian")
            sizes.append(PERSON)
            continue
        lane = a % LANES
        x0 = (a // LANES) * spacing + rng.uniform(-5.0, 5.0)
        v0 = rng.uniform(6.0, 16.0)
        dv = rng.uniform(-3.0, 3.0)
        v = np.clip(v0 + dv * np.clip((times - 3.0) / 3.0, 0.0, 1.0), 0.0, None)
        x = x0 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * DT)])
        xy[a] = np.stack([x, np.full(t_count, lane * LANE_W)], 1)
        speed[a] = v
        cats.append("vehicle")
        sizes.append(CAR)
    return AgentStates(object_ids=("ego", *(f"a{k}" for k in range(1, n_agents))), categories=tuple(cats),
                       sources=("log",) * n_agents, node_ids=np.full(n_agents, -1), frame_idx=np.arange(t_count),
                       times=times, xy=xy, z=np.zeros((n_agents, t_count)), heading=heading, speed=speed,
                       size=np.array(sizes, float), valid=np.ones((n_agents, t_count), bool))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--agents", type=int, nargs="+", default=[10, 25, 50, 100, 200])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    try:
        import torch

        torch.set_num_threads(1)
    except ImportError:  # torch is optional here: the predictor is numpy only
        pass
    mp = road()
    predictor = ReactivePredictor()
    rows = []
    print(f"{'agents':>6} {'median_s':>9} {'min_s':>7} {'driven':>6} {'refined':>7} {'replayed':>8} "
          f"{'coll_log':>8} {'coll_roll':>9}")
    for n in args.agents:
        st = scene(n)
        req = RolloutRequest(st, HISTORY, np.array([0]), mp)
        predictor.rollout(req)  # warm-up
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            out = predictor.rollout(req)
            times.append(time.perf_counter() - t0)
        free = np.arange(1, n)
        coll_log = int(collision_steps(st, free, count_log_pairs=True).pairs[..., HISTORY:].any(axis=(1, 2)).sum())
        coll_roll = int(collision_steps(out.states, free, count_log_pairs=True).pairs[..., HISTORY:].any(axis=(1, 2))
                        .sum())
        row = {"agents": n, "future_steps": FUTURE, "median_s": statistics.median(times), "min_s": min(times),
               "driven": n - 1 - len(out.replayed), "refined": out.states.sources.count("refined"),
               "replayed": len(out.replayed), "agents_colliding_log": coll_log, "agents_colliding_rollout": coll_roll}
        rows.append(row)
        print(f"{n:>6} {row['median_s']:>9.3f} {row['min_s']:>7.3f} {row['driven']:>6} {row['refined']:>7} "
              f"{row['replayed']:>8} {coll_log:>8} {coll_roll:>9}")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({
        "benchmark": "ReactivePredictor.rollout, single thread", "history_steps": HISTORY, "future_steps": FUTURE,
        "dt_s": DT, "lanes": LANES, "repeats": args.repeats, "target": "<= 1 s for 100 agents x 80 steps",
        "machine": {"python": platform.python_version(), "processor": platform.processor() or platform.machine(),
                    "numpy": np.__version__},
        "rows": rows}, indent=2) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
