"""Output trees, clips and frames of `rocc compile` (layout and fields: docs/output.md)."""

import json
import os

import numpy as np

BOX_FIELDS = ("x", "y", "z", "l", "w", "h", "yaw")
# The lamps of a box's `states` in `boxes.json` (docs/output.md, "Vehicle states").
LAMPS = ("headlights", "brake_lights", "hazards", "beacons", "siren")


class NotAnOutputError(ValueError):
    """The directory holds no `rocc compile` output."""


class IncompleteClipError(ValueError):
    """A clip directory was left half-written (an interrupted compile): re-run the same
    `rocc compile` command to finish it, or pass `skip_incomplete=True`."""


def _json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def read_index(root):
    """`root/index.jsonl` as written by `rocc compile`: a list of clip records (dir, scenario,
    ego, rate_hz, frames with paths, timestamps and ego poses), one per finished clip."""
    return list(iter_index(root))


def iter_index(root):
    """The clip records of `root/index.jsonl`, one at a time (a corpus index can be large)."""
    path = os.path.join(root, "index.jsonl")
    if not os.path.isfile(path):
        raise NotAnOutputError(f"{path}: no index (is {root} an output root of `rocc compile -o`?)")
    with open(path, encoding="utf-8") as f:
        head = json.loads(f.readline() or "{}")
        if head.get("format") != "rocc-index":
            raise NotAnOutputError(f"{path}: not a rocc index")
        for line in f:
            yield json.loads(line)


def _manifest(path):
    """The manifest at `path` if it is one of rocc's, else None."""
    try:
        m = _json(path)
    except (OSError, ValueError):
        return None
    return m if isinstance(m, dict) and m.get("compiler") == "rocc" else None


def _looks_like_clip(d):
    return any(os.path.isdir(os.path.join(d, s)) for s in ("bev", "occ", "lidar")) or os.path.isfile(
        os.path.join(d, "boxes.json")
    )


class OutputTree:
    """Every finished clip under `root` (`root/<scenario>/<ego>/`), sorted by directory, and
    their frames as one flat sequence (`len(tree)`, `tree.frame(i)`).

    Raises NotAnOutputError when `root` holds no clip, IncompleteClipError for a half-written
    clip (unless `skip_incomplete`, which leaves it out and names it in `tree.skipped`)."""

    def __init__(self, root, skip_incomplete=False):
        self.root = os.fspath(root)
        if not os.path.isdir(self.root):
            raise NotAnOutputError(f"{self.root}: no such directory")
        self.clips = []
        self.skipped = []
        for scenario in sorted(os.listdir(self.root)):
            sdir = os.path.join(self.root, scenario)
            if not os.path.isdir(sdir):
                continue
            for ego in sorted(os.listdir(sdir)):
                d = os.path.join(sdir, ego)
                if not os.path.isdir(d):
                    continue
                try:
                    clip = Clip.open(d, f"{scenario}/{ego}")
                except IncompleteClipError:
                    if not skip_incomplete:
                        raise
                    self.skipped.append(f"{scenario}/{ego}")
                    continue
                if clip is not None:
                    self.clips.append(clip)
        if not self.clips:
            why = f" ({len(self.skipped)} half-written clips skipped)" if self.skipped else ""
            raise NotAnOutputError(
                f"{self.root}: no finished clip of `rocc compile` here{why}; expected "
                "<root>/<scenario>/<ego>/manifest.json"
            )
        self._flat = [(c, k) for c in self.clips for k in range(len(c))]

    def __len__(self):
        return len(self._flat)

    def frame(self, i):
        clip, k = self._flat[i]
        return clip[k]

    def __iter__(self):
        return (self.frame(i) for i in range(len(self)))

    def clip(self, name):
        """The clip `<scenario>/<ego>`."""
        for c in self.clips:
            if c.dir == name:
                return c
        raise KeyError(name)


class Clip:
    """One ego's frames of one scenario. `frames` are the frame indices written; `clip[k]` is the
    k-th of them. `scene` is the vector map (world frame) or None for a clip without one."""

    def __init__(self, path, name, manifest):
        self.path = path
        self.dir = name
        self.scenario, self.ego = name.split("/")
        self.manifest = manifest
        self.rate_hz = float(manifest["rate_hz"])
        self.stage = manifest["stage"]
        self.frames = list(manifest["frames"])
        self._boxes = None
        self._scene = None

    @staticmethod
    def open(path, name):
        """The clip in `path`; None for a directory that is no clip; IncompleteClipError for one
        left half-written."""
        mpath = os.path.join(path, "manifest.json")
        if not os.path.exists(mpath):
            if _looks_like_clip(path):
                raise IncompleteClipError(
                    f"{path}: half-written clip (no manifest.json: its compile was interrupted); "
                    "re-run the same `rocc compile` command to finish it"
                )
            return None
        m = _manifest(mpath)
        if m is None:
            if _looks_like_clip(path):
                raise IncompleteClipError(f"{mpath}: not a rocc manifest")
            return None
        for f in m.get("files", []):
            p = os.path.join(path, f["path"])
            if not os.path.isfile(p) or os.path.getsize(p) != f["bytes"]:
                raise IncompleteClipError(
                    f"{path}: `{f['path']}` is missing or not the size its manifest lists; "
                    "re-run the same `rocc compile` command to rewrite it"
                )
        return Clip(path, name, m)

    def __len__(self):
        return len(self.frames)

    def __getitem__(self, k):
        if not -len(self) <= k < len(self):
            raise IndexError(f"{self.dir} has {len(self)} frames")
        return Frame(self, self.frames[k], self.boxes_json[k])

    @property
    def boxes_json(self):
        if self._boxes is None:
            recs = _json(os.path.join(self.path, "boxes.json"))
            by_frame = {r["frame"]: r for r in recs}
            self._boxes = [by_frame[f] for f in self.frames]
        return self._boxes

    @property
    def scene(self):
        """{class: [ (K, 2) float64 arrays of world x, y ]} for lane_centrelines, lane_dividers,
        road_boundaries, crosswalks, stop_lines."""
        p = os.path.join(self.path, "scene.json")
        if self._scene is None and os.path.isfile(p):
            s = _json(p)
            classes = ("lane_centrelines", "lane_dividers", "road_boundaries", "crosswalks", "stop_lines")
            self._scene = {c: [np.asarray(l, dtype=np.float64).reshape(-1, 2) for l in s[c]] for c in classes}
        return self._scene

    def ego2global(self):
        """(T, 4, 4) ego-to-world matrices of the written frames."""
        return np.stack([self[k].ego2global for k in range(len(self))])


class Frame:
    """One frame of a clip. Arrays load on first access; everything is in the ego frame of this
    frame except `ego_pose`, `ego2global` and the `*_world` motion fields."""

    def __init__(self, clip, index, rec):
        self.clip = clip
        self.index = index
        self.t = float(rec["t"])
        self.timestamp_us = rec.get("timestamp_us")
        self.ego = rec.get("ego")
        self._rec = rec

    def _file(self, rel):
        return os.path.join(self.clip.path, rel)

    @property
    def has_occupancy(self):
        return self.clip.stage in ("occ", "lidar")

    @property
    def has_lidar(self):
        return self.clip.stage == "lidar"

    @property
    def has_visibility(self):
        return self.has_occupancy and self.clip.manifest.get("visibility") is not None

    @property
    def labels(self):
        """Occ3D's `gts/NNNNNN/labels.npz` (`rocc compile --visibility`): `semantics` (the
        occupancy labels), `mask_lidar` and `mask_camera`, each (400, 400, 32) uint8, the masks
        0 or 1 (Occ3D's loaders cast them with `.astype(bool)`); None without `--visibility`."""
        if not self.has_visibility:
            return None
        with np.load(self._file(f"gts/{self.index:06d}/labels.npz")) as z:
            return {k: z[k] for k in z.files}

    @property
    def bev(self):
        """The BEV `.npz`: gt_bev_masks (18, 400, 400) int8, gt_aux_bev (7, 400, 400) int32,
        structure (400, 400) int8."""
        with np.load(self._file(f"bev/{self.index:06d}.npz")) as z:
            return {k: z[k] for k in z.files}

    @property
    def bev_masks(self):
        return self.bev["gt_bev_masks"]

    @property
    def occupancy(self):
        """(400, 400, 32) uint8 labels 0..8, axes [x, y, z]; None at `--stage bev`."""
        if not self.has_occupancy:
            return None
        return np.load(self._file(f"occ/{self.index:06d}.npy"))

    @property
    def lidar(self):
        """(N, 4) float32 x, y, z, intensity; None below `--stage lidar`."""
        if not self.has_lidar:
            return None
        return np.fromfile(self._file(f"lidar/{self.index:06d}.bin"), dtype=np.float32).reshape(-1, 4)

    @property
    def ego_pose(self):
        """[x, y, z, yaw] of the ego in the world (m, rad), or None."""
        e = self.ego
        return None if e is None else np.array([e["x"], e["y"], e["z"], e["yaw"]])

    @property
    def ego2global(self):
        """(4, 4) float64: world point = ego2global @ [ego point, 1]; None for a clip compiled
        without ego poses."""
        return None if self.ego is None else np.asarray(self.ego["ego2global"], dtype=np.float64)

    @property
    def boxes(self):
        """Arrays over this frame's M boxes: `box` (M, 7) [x, y, z, l, w, h, yaw], `class` (M,)
        int, `velocity`, `acceleration`, `velocity_world`, `acceleration_world` (M, 2),
        `yaw_rate` (M,) (NaN where a box has no motion), and lists `agent`, `kind`,
        `instance_id`; the lamps `headlights`, `brake_lights`, `hazards`, `beacons`, `siren`
        (M,) bool (False for a box without `states`: walkers, objects) and `doors`, per box a
        dict of each open door's angle in degrees (docs/output.md, "Vehicle states")."""
        bs = self._rec["boxes"]
        out = {
            "box": np.array([[b[k] for k in BOX_FIELDS] for b in bs], dtype=np.float64).reshape(-1, 7),
            "class": np.array([b["class"] for b in bs], dtype=np.int64),
            "agent": [b["agent"] for b in bs],
            "kind": [b["kind"] for b in bs],
            "instance_id": [b.get("instance_id") for b in bs],
        }
        nan2 = [np.nan, np.nan]
        for k in ("velocity", "acceleration", "velocity_world", "acceleration_world"):
            out[k] = np.array([b.get(k, nan2) for b in bs], dtype=np.float64).reshape(-1, 2)
        out["yaw_rate"] = np.array([b.get("yaw_rate", np.nan) for b in bs], dtype=np.float64)
        for k in LAMPS:
            out[k] = np.array([bool(b.get("states", {}).get(k, False)) for b in bs], dtype=bool)
        out["doors"] = [dict(b.get("states", {}).get("doors", {})) for b in bs]
        return out
