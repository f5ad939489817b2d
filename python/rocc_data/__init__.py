"""Read a `rocc compile` output tree as clips and frames, with numpy only.

    from rocc_data import OutputTree
    tree = OutputTree("out")                 # every finished clip below out/
    frame = tree.frame(0)                    # the first frame of the first clip
    frame.bev_masks, frame.occupancy, frame.lidar, frame.boxes, frame.ego2global

A clip is finished when its manifest.json exists and every file it lists is there with the listed
size (what `rocc compile` checks before it resumes). `RoccDataset` (a `torch.utils.data.Dataset`)
is available when torch is importable. File formats: docs/output.md.
"""

from .tree import Clip, Frame, IncompleteClipError, NotAnOutputError, OutputTree, iter_index, read_index

__all__ = ["Clip", "Frame", "IncompleteClipError", "NotAnOutputError", "OutputTree", "iter_index", "read_index"]

try:  # torch is optional
    from .torch_dataset import RoccDataset  # noqa: F401

    __all__.append("RoccDataset")
except ImportError:
    pass
