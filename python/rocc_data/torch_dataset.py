"""`RoccDataset`: an output tree's frames as a `torch.utils.data.Dataset` of tensors."""

import numpy as np
import torch
from torch.utils.data import Dataset

from .tree import OutputTree


class RoccDataset(Dataset):
    """Frame i of the tree as a dict of tensors: `bev_masks` (18, 400, 400) int8, `occupancy`
    (400, 400, 32) uint8 when compiled, `lidar` (N, 4) float32 when compiled, `boxes` (M, 7)
    float64 [x, y, z, l, w, h, yaw] in the ego frame, `labels` (M,) int64, `velocity` (M, 2),
    `ego2global` (4, 4) float64 (when recorded), and `clip`, `frame`, `t` for bookkeeping."""

    def __init__(self, root, skip_incomplete=False):
        self.tree = OutputTree(root, skip_incomplete=skip_incomplete)

    def __len__(self):
        return len(self.tree)

    def __getitem__(self, i):
        f = self.tree.frame(i)
        out = {
            "clip": f.clip.dir,
            "frame": f.index,
            "t": f.t,
            "bev_masks": torch.from_numpy(f.bev_masks),
            "boxes": torch.from_numpy(f.boxes["box"]),
            "labels": torch.from_numpy(f.boxes["class"].astype(np.int64)),
            "velocity": torch.from_numpy(f.boxes["velocity"]),
        }
        if f.ego2global is not None:
            out["ego2global"] = torch.from_numpy(f.ego2global)
        if f.has_occupancy:
            out["occupancy"] = torch.from_numpy(f.occupancy)
        if f.has_lidar:
            out["lidar"] = torch.from_numpy(f.lidar)
        return out
