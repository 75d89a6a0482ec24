"""``bench/device_check.py --cpu --tiny``: the device check's CPU variant runs and records agreement."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench" / "device_check.py"


def test_device_check_cpu_variant_writes_its_report(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("device_check", BENCH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "device_check.json"
    report = module.main(["--cpu", "--tiny", "--reps", "1", "--out", str(out)])
    assert json.loads(out.read_text()) == json.loads(json.dumps(report))
    agreement = report["agreement"]
    assert agreement["rgb_max_abs"] < 1e-3 and agreement["alpha_max_abs"] < 1e-3
    assert agreement["expected_depth_max_abs_m"] < 1e-2
    for name in ("means", "quats", "scales", "opacities", "colors"):
        assert agreement[f"grad_{name}_max_abs"] <= 1e-3 * max(1.0, agreement[f"grad_{name}_max_ref"])
    assert report["backend"] == "cpu" and report["reconstruct"]["iterations"] == 4
    assert report["rasterizer_fwd_bwd_ms"] > 0 and report["train_step_ms"] > 0
