"""Check that rocc's occupancy and LiDAR files load like nuPlan-Occ / KITTI / PCD data.

Usage: python3 check_occ_lidar.py OCC.npy CLOUD.bin CLOUD.pcd
Exits non-zero with a message on the first violated property; prints `ok` and a summary.
Needs numpy; also loads the .pcd with Open3D when it is installed.
"""

import sys

import numpy as np

GRID = (400, 400, 32)
VOXEL = 0.25
LOWER = np.array([-50.0, -50.0, -3.0])
K_GROUND = 11
PCD_DTYPE = np.dtype(
    [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"), ("ring", "<u2"), ("lidar", "u1")]
)


def read_pcd(path):
    with open(path, "rb") as f:
        header = {}
        while True:
            line = f.readline()
            assert line, f"{path}: header ends before DATA"
            text = line.decode("ascii").strip()
            if text.startswith("#") or not text:
                continue
            key, _, value = text.partition(" ")
            header[key] = value.split()
            if key == "DATA":
                break
        assert header["VERSION"] == ["0.7"], header["VERSION"]
        assert header["FIELDS"] == ["x", "y", "z", "intensity", "ring", "lidar"], header["FIELDS"]
        assert header["DATA"] == ["binary"], header["DATA"]
        n = int(header["POINTS"][0])
        data = np.frombuffer(f.read(), dtype=PCD_DTYPE)
    assert len(data) == n, f"{path}: {len(data)} points, header says {n}"
    return data


def main(occ_path, bin_path, pcd_path):
    occ = np.load(occ_path)
    assert occ.dtype == np.uint8, f"occ dtype {occ.dtype}"
    assert occ.shape == GRID, f"occ shape {occ.shape}"
    assert occ.max() <= 8, f"label {occ.max()} > 8"
    assert (occ[:, :, K_GROUND] == 1).all(), "ground layer k=11 is not all background"

    pts = np.fromfile(bin_path, dtype="<f4").reshape(-1, 4)
    assert len(pts) > 0, "empty cloud"
    assert np.isfinite(pts).all(), "non-finite values in .bin"
    assert ((pts[:, 3] >= 0) & (pts[:, 3] <= 255)).all(), "intensity outside 0..255"

    pcd = read_pcd(pcd_path)
    assert len(pcd) == len(pts), f".pcd has {len(pcd)} points, .bin {len(pts)}"
    for i, k in enumerate("xyz"):
        assert np.array_equal(pcd[k], pts[:, i]), f".pcd {k} differs from .bin"
    assert np.array_equal(pcd["intensity"], pts[:, 3]), ".pcd intensity differs from .bin"
    assert set(np.unique(pcd["lidar"]).tolist()) <= {0, 1, 2, 3, 4}, "unknown lidar id"

    # Every point is in or on the boundary of a non-free voxel.
    xyz = pts[:, :3].astype(np.float64)
    hit = np.zeros(len(xyz), dtype=bool)
    eps = 1e-4
    for dx in (-eps, eps):
        for dy in (-eps, eps):
            for dz in (-eps, eps):
                idx = np.floor((xyz + [dx, dy, dz] - LOWER) / VOXEL).astype(np.int64)
                idx = np.clip(idx, 0, np.array(GRID) - 1)
                hit |= occ[idx[:, 0], idx[:, 1], idx[:, 2]] != 0
    assert hit.all(), f"{(~hit).sum()} points in free voxels"

    try:
        import open3d as o3d  # optional

        t = o3d.t.io.read_point_cloud(pcd_path)
        assert len(t.point.positions) == len(pts), "Open3D read a different point count"
        print("open3d ok")
    except ImportError:
        pass
    print(f"ok {len(pts)} points, occupied voxels {(occ != 0).sum()}")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
