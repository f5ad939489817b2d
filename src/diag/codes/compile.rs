//! E03xx: compile options.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0301",
        title: "unknown ego",
        explanation: "`rocc compile --ego NAME` names an agent the scenario does not declare, or one that cannot\n\
carry sensors (a static object or a row element). Egos are declared agents; background traffic\n\
and rows have generated names that may change with the seed.\n
    rocc compile scenarios/fire_lane.scn --ego ambulance -o out     // error if no agent is called `ambulance`\n\n\
`rocc check FILE` prints the scenario's egos; any declared mover may be chosen.",
    },
    Code {
        code: "E0302",
        title: "bad frame selection",
        explanation: "`--frames` takes a comma-separated list of frame indices and ranges: `0`, `0..10` (10\n\
excluded), `0..=10`, `50..` (to the end), e.g. `--frames 0,10..20`. Every index must be below the\n\
clip's frame count (duration x rate).\n
    $ rocc compile s.scn -o out --frames 0,10..20     // fine
    $ rocc compile s.scn -o out --frames 10..5        // error: empty range
    $ rocc compile s.scn -o out --frames 500          // error when the clip has 80 frames",
    },
    Code {
        code: "E0303",
        title: "two inputs write the same output directory",
        explanation: "Outputs go to OUT/<scenario>/<ego>/, so two files in one batch that declare the same\n\
scenario name would overwrite each other. Rename one of the scenarios (`scenario NAME { ... }`).\n
    // a.scn and b.scn both say `scenario cut_in { ... }`
    $ rocc compile a.scn b.scn -o out      // error: both write out/cut_in/",
    },
    Code {
        code: "E0304",
        title: "bad sensor rig file",
        explanation: "`--rig FILE` must be a RON rig description like `rigs/nuplan.ron`: a name, horizontal\n\
resolution, range limits, one reflectivity per occupancy label (9), the intensity, drop and noise\n\
models, and at least one sensor with beam elevations and an azimuth sector.\n
    $ rocc compile s.scn -o out --rig rigs/nuplan.ron     // fine
    $ rocc compile s.scn -o out --rig my_rig.ron         // error if a field is missing or no sensor is given",
    },
];
