//! E07xx: import, edit and eval.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0701",
        title: "unreadable occupancy frame",
        explanation: "`rocc eval occ` reads occupancy frames as a dense `.npy` of shape (400, 400, 32) (rocc's\n\
uint8 output, or nuPlan-Occ's dense grid in any integer dtype) or as a sparse `.npz` whose array\n\
is (N, 4) rows of [i, j, k, label] (unlisted voxels are free). Labels are 0..=8 (docs/output.md\n\
lists them).\n
    $ rocc eval occ --pred pred/ --gt gt/    // error if a frame is (200, 200, 16) or holds label 12",
    },
    Code {
        code: "E0703",
        title: "prediction and ground-truth sets do not match",
        explanation: "`--pred` and `--gt` must be directories. Occupancy frames are paired by relative path\n\
(`.npy` and `.npz` may stand in for each other); every ground-truth frame needs a prediction.\n\
LiDAR sets are compared as sets and need at least one cloud each: a clip compiled with\n\
`--stage occ` has none (its `occ/*.npy` are not clouds).\n
    $ rocc eval occ --pred pred/ --gt gt/    // error if gt/scene/0007.npy has no pred/scene/0007.np[yz]
    $ rocc eval occ --pred pred.npy --gt gt/  // error: --pred must be a directory",
    },
    Code {
        code: "E0704",
        title: "unreadable point cloud",
        explanation: "`rocc eval lidar` reads KITTI-style `.bin` (float32 x, y, z, intensity per point), PCD v0.7\n\
(`DATA ascii` or `binary`, float fields x, y, z) or a `.npy` of shape (N, >= 3), float32 or\n\
float64. In a compiled clip directory only `lidar/` is read.\n
    $ rocc eval lidar --pred pred/ --gt gt/  // error if a .bin length is not a multiple of 16 bytes",
    },
    Code {
        code: "E0705",
        title: "box stream is not valid JSON of the expected layout",
        explanation: "`rocc import boxes FILE` reads\n
    { \"rate_hz\": 2.0, \"ego_size\": [l, w, h], \"sensor_to_ego\": {\"x\": 0, \"y\": 0, \"yaw\": 0},
      \"frames\": [ { \"frame\": 0, \"time\": 0.0,
          \"ego_pose\": {\"x\": 1.0, \"y\": 2.0, \"yaw\": 0.1},
          \"boxes\": [ {\"track\": \"a1\", \"class\": \"vehicle.car\",
                      \"center\": [x, y, z], \"size\": [a, b, c], \"yaw\": 0.3} ] } ] }\n\n\
Only `frames` is required. `ego_pose` may also be {\"translation\": [x, y, z], \"rotation\":\n\
[w, x, y, z]}. With `--convention mmdet3d` a box may be `\"box\": [cx, cy, cz, w, l, h, yaw]`.",
    },
    Code {
        code: "E0706",
        title: "box stream values are inconsistent",
        explanation: "The frames of a box stream must have distinct indices and increasing times, a rate in\n\
0.5..100 Hz (from `rate_hz` or the median frame interval), at most 120 s in all, and finite\n\
numbers. A `convention` written in the file must agree with `--convention`.\n
    $ rocc import boxes clip.json -o clip.scn   // error if two frames both have \"frame\": 3",
    },
    Code {
        code: "E0707",
        title: "recorded coordinates too far apart",
        explanation: "Replayed coordinates in a `.scn` stay within 1 km of the scenario's origin. The importer\n\
moves the origin (by whole kilometres) to the clip's first ego pose when the recording uses\n\
large coordinates (nuPlan's UTM metres); a clip that still spans more must be split.\n
    $ rocc import boxes long_drive.json -o drive.scn   // error: ego travels 3 km; split the clip",
    },
    Code {
        code: "E0708",
        title: "bad static BEV",
        explanation: "`--static-bev` takes a nuPlan-Occ BEV `.npz` (key `gt_bev_masks`, int8 (18, 400, 400)),\n\
whose channels 0-7 and 15-17 replace the map's in every frame, or a directory of per-frame\n\
`NNNNNN.npz` files (a compiled clip's `bev/`), matched by frame index.\n
    $ rocc import boxes clip.json -o clip.scn --static-bev bev.npz   // error if gt_bev_masks is (16, 200, 200)",
    },
    Code {
        code: "E0709",
        title: "edit names an unknown agent",
        explanation: "`--delete AGENT` and `--move AGENT by DX,DY` name an agent by the name in `boxes.json`\n\
(clips) or the declaration (`.scn`). Row elements and background traffic have generated names;\n\
`boxes.json` lists them.\n
    $ rocc edit out/cut_in/ego --delete cuter   // error: no agent `cuter` in boxes.json",
    },
    Code {
        code: "E0710",
        title: "edited box off a valid surface",
        explanation: "An inserted or moved box must stand where the BEV's map layers allow its class:\n\
vehicles on drivable area (channels 0, 1, 3, 5, 6), bicycles there or on walkways and\n\
crosswalks; people (as the checker places them: standing or lying on a lane included) and static\n\
objects anywhere in the 100 m grid. The check is at the box centre, in every edited frame.\n
    $ rocc edit out/cut_in/ego --insert sedan at 20,40   // error: a car off the road",
    },
    Code {
        code: "E0711",
        title: "edited box overlaps another",
        explanation: "An inserted or moved box may touch another box or the ego but not interpenetrate it\n\
(more than 1 cm per side). Choose a free spot; `boxes.json` lists every box of every frame.\n
    $ rocc edit out/cut_in/ego --insert sedan at 2,0   // error: overlaps the ego",
    },
    Code {
        code: "E0712",
        title: "not an editable clip",
        explanation: "`rocc edit DIR` needs a directory written by `rocc compile` (manifest.json, boxes.json,\n\
bev/). The later stages need the scene the clip came from (ego poses, background), so the\n\
scenario named in the manifest must be readable and unchanged (same hash); pass `--scenario\n\
FILE` when it moved. A clip compiled with a custom rig needs the same `--rig`. A clip of the\n\
learned backend is rerun with the weights its manifest records (or `--weights FILE`), which must\n\
be the same weights (the hash in the manifest's `backend`).\n
    $ rocc edit out/cut_in/ego/bev --delete cutter   // error: no manifest.json in bev/",
    },
    Code {
        code: "E0713",
        title: "unknown kind",
        explanation: "`--insert KIND at X,Y` takes a kind of the stdlib prelude (stdlib/kinds.scn), e.g.\n\
sedan, van, bicycle, pedestrian, traffic_cone, barrier, construction_sign, debris.\n
    $ rocc edit out/cut_in/ego --insert tractor at 20,3.5   // error: unknown kind `tractor`",
    },
    Code {
        code: "E0714",
        title: "edit does not apply to this scenario",
        explanation: "On a `.scn`, `--move` shifts agents placed at world coordinates `(X m, Y m)` or replaying\n\
a `track`; an agent placed relative to the road moves by changing its distance or `offset`.\n\
The file must declare a scenario.\n
    $ rocc edit cut_in.scn --move cutter by 0,1   // error if `cutter` is placed 20 m before center",
    },
    Code {
        code: "E0715",
        title: "unknown class imported as generic_object",
        explanation: "A warning: a box's class name is neither a nuPlan class nor a nuScenes or mmdet3d name\n\
rocc knows. The box is kept, as `generic_object` (kind `debris`), never dropped. Known:\n\
vehicle, bicycle, pedestrian, traffic_cone, barrier, czone_sign, generic_object; vehicle.*,\n\
human.pedestrian.*, movable_object.{trafficcone, barrier, debris, pushable_pullable},\n\
static_object.bicycle_rack, animal; car, truck, bus, trailer, construction_vehicle,\n\
motorcycle (nuPlan counts two-wheelers as bicycle).\n
    $ rocc import boxes clip.json -o clip.scn   // warning: class `vehicle.hovercraft` imported as generic_object",
    },
    Code {
        code: "E0716",
        title: "box imported with a change",
        explanation: "A warning: a box could not be replayed exactly — its size was outside 0.05..40 m\n\
(clamped), its track changed size (a replayed agent keeps its first size), or the track had two\n\
boxes in one frame (the second dropped). That frame's BEV footprint differs from the recording's.\n
    $ rocc import boxes clip.json -o clip.scn   // warning: track a1 changed size in frame 12; first size kept",
    },
    Code {
        code: "E0717",
        title: "malformed edit",
        explanation: "Edits are written\n
    --insert KIND at X,Y [yaw A]    A in degrees, or with `rad`
    --delete AGENT
    --move AGENT by DX,DY\n\n\
Coordinates are metres: for a compiled clip, in the ego frame (x forward, y left) of the first\n\
edited frame, and the edit then stays fixed in the world in every other frame; for a `.scn`, in\n\
the scenario's world frame.",
    },
    Code {
        code: "E0718",
        title: "edit selects no compiled frame",
        explanation: "`rocc edit CLIP --frames SPEC` edits only frames the clip holds: `rocc compile --frames`
may have written a subset (manifest.json lists them under `frames`). None of the frames SPEC
names was compiled, so the edit would change nothing; nothing is written. Pick frames from the
manifest, or recompile the clip with the frames to edit.

    rocc compile scenarios/replayed_cut_in.scn -o out --frames 0..2
    rocc edit out/replayed_cut_in/ego --frames 20..25 --delete cutter   // error: frames 20..25 were not compiled",
    },
];
