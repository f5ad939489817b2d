//! E04xx: I/O, outputs and the dataset files.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0401",
        title: "cannot write output",
        explanation: "An output file or directory could not be created or written. rocc writes to a\n\
temporary name and renames, so no truncated file is left behind.\n
    $ rocc compile s.scn -o /read-only/out    // error: permission denied",
    },
    Code {
        code: "E0402",
        title: "bad --shard",
        explanation: "`--shard K/N` runs the K-th of N parts of a batch (1 <= K <= N), so that N jobs of an\n\
array (a Slurm array, a Kubernetes indexed job) split the sorted input list without talking to\n\
each other: job K compiles every N-th file starting at the K-th.\n
    $ rocc compile scenarios/ -o out --shard 3/16    // fine: the third of 16 parts
    $ rocc compile scenarios/ -o out --shard 0/16    // error: K counts from 1
    $ rocc compile scenarios/ -o out --shard 3       // error: expected K/N",
    },
    Code {
        code: "E0403",
        title: "output directory holds an edited clip",
        explanation: "`rocc edit` changed this clip after it was compiled (its manifest.json lists the edits).\n\
Compiling the same scenario into the same directory would rewrite the clip from the scenario and\n\
lose those edits, so `rocc compile` leaves it alone and reports this error; the other clips are\n\
still compiled. Pass `--force` to recompile it anyway (the edits are discarded), compile into\n\
another `-o` directory, or, to keep an edit for good, apply it to the `.scn` (`rocc edit\n\
FILE.scn ... -o edited.scn`) and compile that.\n
    $ rocc compile scenarios/replayed_cut_in.scn -o out
    $ rocc edit out/replayed_cut_in/ego --delete cutter
    $ rocc compile scenarios/replayed_cut_in.scn -o out           // error: the clip was edited
    $ rocc compile scenarios/replayed_cut_in.scn -o out --force   // recompiles, edits discarded",
    },
    Code {
        code: "E0410",
        title: "cannot write the dataset index",
        explanation: "After a batch, `rocc compile` rebuilds `index.jsonl` at the output root from every finished\n\
clip below it (docs/compile.md, \"Dataset index\"). The clips themselves are written; only the index\n\
could not be (permissions, a full disk, or an `index.jsonl` that is a directory). Fix the cause and\n\
re-run the same command: complete clips are kept and the index is rebuilt.\n
    $ rocc compile scenarios/ -o out     // error if out/index.jsonl cannot be replaced",
    },
    Code {
        code: "E0430",
        title: "--flow without occupancy",
        explanation: "`--flow` writes the velocity of every occupied voxel of a moving agent\n\
(`flow/NNNNNN.npz`, docs/output.md \"Occupancy flow\"), so it needs the occupancy stage:\n\
`--stage occ` or `--stage lidar` (the default).\n
    $ rocc compile scenarios/ -o out --flow                 // fine: all stages
    $ rocc compile scenarios/ -o out --stage bev --flow     // error: no occupancy to give flow to",
    },
    Code {
        code: "E0431",
        title: "bad camera rig",
        explanation: "`--camera-rig FILE` (used by `--visibility` for `mask_camera`) is a RON file in the form of\n\
rigs/nuplan_cameras.ron: `name`, `ray_stride_px` (one ray per that many pixels, 1 up to the\n\
smallest image side) and `cameras`, each with `name`, `origin` (x, y, z in metres, ego frame),\n\
`yaw_deg`, `pitch_deg` (positive looks down), `hfov_deg` (1 to 170) and `width`, `height`\n\
(pixels, 1 to 16384). The file could not be read, did not parse, or broke one of these rules.\n
    $ rocc compile scene.scn -o out --visibility --camera-rig my_cameras.ron",
    },
    Code {
        code: "E0432",
        title: "--visibility without occupancy",
        explanation: "`--visibility` writes Occ3D's `gts/NNNNNN/labels.npz` (the occupancy labels with LiDAR and\n\
camera visibility masks, docs/output.md \"Visibility\"), so it needs the occupancy stage:\n\
`--stage occ` or `--stage lidar` (the default).\n
    $ rocc compile scenarios/ -o out --visibility                 // fine: all stages
    $ rocc compile scenarios/ -o out --stage bev --visibility     // error: no occupancy",
    },
    Code {
        code: "E0433",
        title: "--camera-rig without --visibility",
        explanation: "`--camera-rig FILE` only chooses the cameras of `--visibility`'s `mask_camera`; without\n\
`--visibility` nothing would use it.\n
    $ rocc compile scene.scn -o out --visibility --camera-rig my_cameras.ron",
    },
];
