"""Benchmark: the DGP (DDAD format) loader on TRI's public DGP test scene, and a smoke reconstruction of it.

    .venv/bin/python bench/bench_dgp_loader.py [--scene ../shared/data/dgp/scene_02] [--scale 0.125]
                                               [--iterations 150]

Figures: load time; IoU of the projected 3D track boxes against the annotated 2D boxes; median relative
disagreement of lidar depth between frames 0 and 1 in CAMERA_01 with the loader's ego pose and with a wrong
pose (frame 0's); ego-mask share per camera. Then the scene (at ``--scale``) goes through the store (write,
read back) and is reconstructed twice for ``--iterations`` steps on the CPU, with the ego-body masks and with
them removed; both are scored on the held-out views over the valid pixels. Writes
``bench/results/dgp_loader.json`` and ``bench/results/dgp_reconstruct_test_views.png`` (per held-out view:
ground truth with the mask shaded | render with masks | render without masks).
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from run_info import load_average, machine_info, write_json_result

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from simsplat_core.data.dgp import (  # noqa: E402
    find_scene_file,
    lidar_depth,
    load_dgp_scene,
    read_lidar_points,
    sweep_points_world,  # noqa: E402
)
from simsplat_core.data.dgp_format import parse_scene  # noqa: E402
from simsplat_core.geometry import transform_points  # noqa: E402
from simsplat_core.scene import ReconstructionConfig, reconstruct  # noqa: E402
from simsplat_core.scene.evaluate import render_views, summarise  # noqa: E402
from simsplat_core.scene.views import view_batches  # noqa: E402
from simsplat_core.types import SceneLog  # noqa: E402
from storage import ArtifactStore, read_scene_log, write_scene_log  # noqa: E402
from tests.simsplat_core.data.dgp_checks import projected_box_ious  # noqa: E402

logger = logging.getLogger("bench.dgp_loader")
RESULTS = Path(__file__).resolve().parent / "results"


def depth_disagreement(scene_dir: Path, log: SceneLog) -> dict[str, float]:
    """Median relative difference of frame 1's sweep vs frame 0's in frame 0's CAMERA_01, right vs wrong pose."""
    cam = next(img for img in log.images if img.frame_idx == 0 and img.camera == "CAMERA_01")
    reference = lidar_depth(sweep_points_world(scene_dir, 0), cam.K, cam.cam_to_world, cam.width, cam.height)
    lidar = next(d for d in parse_scene(find_scene_file(scene_dir))[1].datums if d.kind == "point_cloud")
    sweep = read_lidar_points(scene_dir / lidar.filename)
    out = {"measured_pixel_share": float(np.isfinite(reference).mean())}
    for name, pose in (("right_pose", log.ego_poses[1]), ("wrong_pose", log.ego_poses[0])):
        depth = lidar_depth(transform_points(pose, sweep), cam.K, cam.cam_to_world, cam.width, cam.height)
        both = np.isfinite(depth) & np.isfinite(reference)
        out[f"median_rel_diff_{name}"] = float(np.median(np.abs(depth[both] - reference[both]) / reference[both]))
    return out


def without_masks(log: SceneLog) -> SceneLog:
    return dataclasses.replace(log, images=tuple(dataclasses.replace(i, valid_mask=None) for i in log.images))


def write_view_sheet(log: SceneLog, masked, unmasked, path: Path) -> None:
    """Rows: held-out views; columns: ground truth (invalid pixels shaded red) | render (masked) | render (unmasked)."""
    valid = {(i.frame_idx, i.camera): i.valid_mask for i in log.images}
    rows = []
    for a, b in zip(masked.test_renders, unmasked.test_renders):
        gt = a.gt_rgb.copy()
        mask = valid[(a.frame_idx, a.camera)]
        if mask is not None:
            gt[~mask] = 0.5 * gt[~mask] + [0.5, 0.0, 0.0]
        row = np.concatenate([gt, a.rgb, b.rgb], axis=1)
        label = f"f{a.frame_idx} {a.camera}: {a.psnr:.1f} dB masked / {b.psnr:.1f} dB unmasked"
        bgr = cv2.cvtColor((np.clip(row, 0, 1) * 255).astype(np.uint8), cv2.COLOR_RGB2BGR)
        cv2.putText(bgr, label, (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 255, 255), 1)
        rows.append(bgr)
    cv2.imwrite(str(path), np.concatenate(rows, axis=0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", type=Path,
                        default=Path(__file__).resolve().parents[1] / "../shared/data/dgp/scene_02")
    parser.add_argument("--scale", type=float, default=0.125)
    parser.add_argument("--iterations", type=int, default=150)
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    scene_dir = args.scene.resolve()
    load_before = load_average()

    t0 = time.perf_counter()
    quarter = load_dgp_scene(scene_dir, image_scale=0.25)
    load_s = time.perf_counter() - t0
    ious = np.array(projected_box_ious(scene_dir, quarter, 0.25))
    mask_share = {}
    for img in quarter.images:
        share = 0.0 if img.valid_mask is None else float(1.0 - img.valid_mask.mean())
        mask_share.setdefault(img.camera, []).append(share)

    log = load_dgp_scene(scene_dir, image_scale=args.scale)
    with tempfile.TemporaryDirectory() as tmp:
        store = ArtifactStore(tmp)
        write_scene_log(store, log)
        stored = read_scene_log(store, log.seq_id)
    config = dataclasses.replace(ReconstructionConfig(), iterations=args.iterations, device="cpu")
    runs = {}
    for name, variant in (("masked", stored), ("unmasked", without_masks(stored))):
        t1 = time.perf_counter()
        runs[name] = reconstruct(variant, config)
        runs[name].metrics["run_wall_s"] = time.perf_counter() - t1
    # both scored over the valid pixels: re-score the unmasked run's renders with the masks
    test_batches = [b for b in view_batches(stored) if b.split == "test"]
    unmasked_on_valid = summarise(render_views(runs["unmasked"].graph, test_batches, stored.objects,
                                               with_node_ids=False), "test")
    sheet = RESULTS / "dgp_reconstruct_test_views.png"
    write_view_sheet(stored, runs["masked"], runs["unmasked"], sheet)

    result = {
        "scene": str(scene_dir.name),
        "machine": machine_info(),
        "load_average_before": load_before,
        "load_average_after": load_average(),
        "load_seconds_quarter_scale": round(load_s, 2),
        "frames": quarter.num_frames,
        "images": len(quarter.images),
        "tracks": len(quarter.tracks),
        "box_projection_vs_2d_boxes": {"pairs": int(ious.size), "iou_median": float(np.median(ious)),
                                       "iou_mean": float(ious.mean()), "iou_min": float(ious.min()),
                                       "share_iou_above_0.5": float((ious > 0.5).mean())},
        "lidar_depth_frame1_into_frame0_CAMERA_01_quarter_scale": depth_disagreement(scene_dir, quarter),
        "ego_mask_share_per_camera": {k: round(float(np.mean(v)), 3) for k, v in sorted(mask_share.items())},
        "reconstruction": {
            "image_scale": args.scale,
            "iterations": args.iterations,
            "held_out_views": [f"f{r.frame_idx} {r.camera}" for r in runs["masked"].test_renders],
            "psnr_test_masked_training_valid_pixels": runs["masked"].metrics["psnr_test"],
            "ssim_test_masked_training_valid_pixels": runs["masked"].metrics["ssim_test"],
            "psnr_test_unmasked_training_valid_pixels": unmasked_on_valid["psnr_test"],
            "psnr_test_unmasked_training_all_pixels": runs["unmasked"].metrics["psnr_test"],
            "psnr_train_masked": runs["masked"].metrics["psnr_train"],
            "num_gaussians_masked": runs["masked"].metrics["num_gaussians"],
            "wall_s_masked": round(runs["masked"].metrics["run_wall_s"], 1),
            "wall_s_unmasked": round(runs["unmasked"].metrics["run_wall_s"], 1),
            "sheet": sheet.name,
        },
    }
    write_json_result(result, RESULTS / "dgp_loader.json")


if __name__ == "__main__":
    main()
