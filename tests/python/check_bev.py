"""Check that a BEV .npz written by rocc loads like a nuPlan-Occ / UniScene-v2 BEV.

Usage: python3 check_bev.py FILE.npz [FILE.npz ...]
Exits non-zero with a message on the first violated property; prints `ok N` otherwise.
Needs numpy only.
"""

import sys

import numpy as np

N_MASKS, N_AUX, GRID = 18, 7, 400
AGENT_CHANNELS = list(range(8, 15))
CH_INTERSECTIONS, CH_ROAD_SEGMENTS, CH_BOUNDARY = 0, 7, 17


def check(path):
    with np.load(path) as z:
        keys = set(z.files)
        assert {"gt_bev_masks", "gt_aux_bev"} <= keys, f"{path}: keys {sorted(keys)}"
        assert keys <= {"gt_bev_masks", "gt_aux_bev", "structure"}, f"{path}: unexpected keys {sorted(keys)}"
        m, a = z["gt_bev_masks"], z["gt_aux_bev"]
        s = z["structure"] if "structure" in keys else None

    assert m.dtype == np.int8, f"{path}: gt_bev_masks dtype {m.dtype}"
    assert m.shape == (N_MASKS, GRID, GRID), f"{path}: gt_bev_masks shape {m.shape}"
    assert a.dtype == np.int32, f"{path}: gt_aux_bev dtype {a.dtype}"
    assert a.shape == (N_AUX, GRID, GRID), f"{path}: gt_aux_bev shape {a.shape}"
    assert set(np.unique(m).tolist()) <= {0, 1}, f"{path}: mask values {np.unique(m)}"
    if s is not None:
        assert s.dtype == np.int8 and s.shape == (GRID, GRID), f"{path}: structure {s.dtype} {s.shape}"
        assert set(np.unique(s).tolist()) <= {0, 1}, f"{path}: structure values {np.unique(s)}"

    # Aux lives only on agent footprints.
    agents = m[AGENT_CHANNELS].any(axis=0)
    assert not (a.any(axis=0) & ~agents).any(), f"{path}: aux set outside every agent footprint"
    assert (a[2:4] >= 0).all(), f"{path}: negative half-length/half-width"
    assert set(np.unique(a[4:6]).tolist()) <= {-1, 0, 1}, f"{path}: heading not a truncated unit vector"
    assert (np.abs(a[0:2]) < 2 * GRID).all(), f"{path}: centre offset out of range"

    # Boundary is part of (road segments U intersections).
    road = (m[CH_ROAD_SEGMENTS] | m[CH_INTERSECTIONS]).astype(bool)
    assert not (m[CH_BOUNDARY].astype(bool) & ~road).any(), f"{path}: boundary outside the road"


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    for p in sys.argv[1:]:
        check(p)
    print(f"ok {len(sys.argv) - 1}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
