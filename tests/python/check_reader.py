"""Check the `rocc_data` reader (python/) on a compiled output tree.

Usage: PYTHONPATH=python python3 check_reader.py OUT NOT_AN_OUTPUT
OUT holds finished clips and one half-written clip (`half_written/ego`: frames, no manifest).
Exits non-zero on the first violated property; prints `ok: C clips, F frames`.
"""

import sys

import numpy as np

import rocc_data
from rocc_data import IncompleteClipError, NotAnOutputError, OutputTree, read_index


def expect_error(kind, words, fn):
    try:
        fn()
    except kind as e:
        assert all(w in str(e) for w in words), f"{kind.__name__} should name {words}: {e}"
        return
    raise AssertionError(f"expected {kind.__name__}")


def main(out, not_output):
    expect_error(IncompleteClipError, ["half_written", "manifest.json", "rocc compile"], lambda: OutputTree(out))
    expect_error(NotAnOutputError, [not_output], lambda: OutputTree(not_output))
    expect_error(NotAnOutputError, ["no such directory"], lambda: OutputTree(not_output + "/missing"))
    expect_error(NotAnOutputError, ["no index"], lambda: read_index(not_output))

    tree = OutputTree(out, skip_incomplete=True)
    assert tree.skipped == ["half_written/ego"], tree.skipped

    # The reader and the index agree: same clips, frames, paths and poses.
    idx = read_index(out)
    assert [c["dir"] for c in idx] == [c.dir for c in tree.clips]
    for ic, clip in zip(idx, tree.clips):
        assert [f["frame"] for f in ic["frames"]] == clip.frames
        for f, fr in zip(ic["frames"], (clip[k] for k in range(len(clip)))):
            assert np.array_equal(np.asarray(f["ego2global"]), fr.ego2global)
            assert f["timestamp_us"] == fr.timestamp_us and abs(f["t"] - fr.t) < 1e-12

    n = 0
    for fr in tree:
        masks = fr.bev_masks
        assert masks.shape == (18, 400, 400) and masks.dtype == np.int8
        occ = fr.occupancy
        assert occ.shape == (400, 400, 32) and occ.dtype == np.uint8 and occ.max() <= 8
        pts = fr.lidar
        assert pts.ndim == 2 and pts.shape[1] == 4 and len(pts) > 100 and pts.dtype == np.float32
        m = fr.ego2global
        assert m.shape == (4, 4) and abs(np.linalg.det(m[:3, :3]) - 1) < 1e-9 and np.array_equal(m[3], [0, 0, 0, 1])
        assert np.allclose(m[:2, 3], fr.ego_pose[:2])
        b = fr.boxes
        k = len(b["agent"])
        assert b["box"].shape == (k, 7) and b["velocity"].shape == (k, 2) and b["class"].shape == (k,)
        assert np.isfinite(b["velocity"]).all() and all(b["instance_id"])
        # Ego-frame velocity is the world velocity in the ego's axes.
        yaw = fr.ego_pose[3]
        c, s = np.cos(yaw), np.sin(yaw)
        rot = np.array([[c, s], [-s, c]])
        assert np.allclose(b["velocity"], b["velocity_world"] @ rot.T, atol=1e-9)
        # Lamps: one flag per box; an ambulance drives with its siren and beacons on.
        for lamp in rocc_data.tree.LAMPS:
            assert b[lamp].shape == (k,) and b[lamp].dtype == bool, lamp
        assert len(b["doors"]) == k
        for kind, siren, beacons in zip(b["kind"], b["siren"], b["beacons"]):
            assert kind != "ambulance" or (siren and beacons), (kind, siren, beacons)
        n += 1
    assert n == len(tree)

    clip = tree.clips[0]
    scene = clip.scene
    assert set(scene) == {"lane_centrelines", "lane_dividers", "road_boundaries", "crosswalks", "stop_lines"}
    assert all(a.ndim == 2 and a.shape[1] == 2 for lines in scene.values() for a in lines)
    assert len(scene["lane_centrelines"]) > 0
    assert clip.ego2global().shape == (len(clip), 4, 4)

    if hasattr(rocc_data, "RoccDataset"):
        ds = rocc_data.RoccDataset(out, skip_incomplete=True)
        item = ds[0]
        assert len(ds) == n and tuple(item["bev_masks"].shape) == (18, 400, 400)
    print(f"ok: {len(tree.clips)} clips, {n} frames")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
