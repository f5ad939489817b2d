"""Check Occ3D's `labels.npz` (`rocc compile --visibility`) as numpy and the `rocc_data` reader
see it.

Usage: PYTHONPATH=python python3 check_labels.py CLIP_DIR
Loads every frame's `gts/NNNNNN/labels.npz` with plain numpy the way Occ3D's loaders do, then
through `rocc_data`; prints `ok: F frames`.
"""

import os
import sys

import numpy as np

from rocc_data import OutputTree


def main(out):
    tree = OutputTree(out)
    n = 0
    for clip in tree.clips:
        for k in range(len(clip)):
            fr = clip[k]
            path = os.path.join(clip.path, f"gts/{fr.index:06d}/labels.npz")
            z = np.load(path)
            assert sorted(z.files) == ["mask_camera", "mask_lidar", "semantics"], z.files
            for key in z.files:
                a = z[key]
                assert a.dtype == np.uint8 and a.shape == (400, 400, 32), (key, a.dtype, a.shape)
            # CVPR2023-occupancy's LoadOccGTFromFile.
            mask_lidar = z["mask_lidar"].astype(bool)
            mask_camera = z["mask_camera"].astype(bool)
            assert set(np.unique(z["mask_lidar"])) <= {0, 1} and set(np.unique(z["mask_camera"])) <= {0, 1}
            assert mask_lidar.any() and mask_camera.any()
            assert np.array_equal(z["semantics"], fr.occupancy)
            labels = fr.labels
            assert labels is not None and all(np.array_equal(labels[k], z[k]) for k in z.files)
            n += 1
    print(f"ok: {n} frames")


if __name__ == "__main__":
    main(sys.argv[1])
