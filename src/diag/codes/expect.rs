//! E10xx: expectations and `rocc test`.

use super::Code;

pub const CODES: &[Code] = &[
    // ---- E10xx: expectations and `rocc test` ----
    Code {
        code: "E1001",
        title: "expectation time outside the clip",
        explanation:
            "An `expect` line's window (`during A..B s` or `by T s`) must lie within the clip, from 0 to the\n\
scenario's `duration`; `by` takes one time, not a range.\n
    duration 6 s
    expect { contact striker with ego by 8 s }     // error: the clip ends at 6 s\n\n\
Shorten the window or lengthen the clip. See docs/library-testing.md.",
    },
    Code {
        code: "E1002",
        title: "landmark not on the agent's lane",
        explanation:
            "`stopped A before LANDMARK` and `reach A LANDMARK` measure along the lane agent A starts in, so\n\
A must be placed on a lane (`at south.in[1], ...`) of a road that has the landmark: stop lines\n\
are on in-lanes of four_way, t_junction and roundabout roads; `junction` needs a junction;\n\
`center` is on every road.\n
    road straight { lanes 2 }
    expect { stopped ego before stop_line }     // error: a straight road has no stop lines\n\n\
`enters A on LIGHT` reads the signal of A's own approach, so A must be placed on an in-lane of a\n\
road with `signals on`.\n
    road four_way { lanes 1 }
    expect { enters runner on red }     // error: the road has no traffic signals",
    },
    Code {
        code: "E1003",
        title: "expectation names one agent twice",
        explanation: "`contact`, `no_contact` and `gap` relate two different agents.\n
    expect { gap ego with ego at_least 2 m }     // error",
    },
    Code {
        code: "E1004",
        title: "agent did not enter on the expected light",
        explanation: "`enters A on red|yellow|green [during A..B s | by T s]` holds when the front of A's box first\n\
passes its stop line (measured along the lane A starts in, as `reach` measures it) within the\n\
window, while the signal of that lane shows the light. The report gives when it entered and the\n\
light it saw, or how far short of the line it stayed. See docs/library-testing.md.\n
    enters runner on red     // a red-light runner
    enters ego on green during 8..14 s",
    },
    Code {
        code: "E1010",
        title: "expected contact did not happen",
        explanation: "`contact A with B [on SIDE] [during A..B s | by T s]` holds when the two boxes overlap within\n\
the window and, with `on`, the overlap lies on that side of B's box (a face such as `rear` also\n\
takes its corners `rear_left` and `rear_right`). The report says how close they came, or when and\n\
on which side they touched instead. See docs/library-testing.md.\n
    contact striker with ego on rear during 2..4 s     // holds when the boxes overlap then, on ego's rear",
    },
    Code {
        code: "E1011",
        title: "unexpected contact",
        explanation:
            "`no_contact` (any two boxes) or `no_contact A with B` holds when the boxes never overlap within\n\
the window. The report names who touched whom, when and on which side.\n
    no_contact                     // any two boxes
    no_contact amb with stalled     // these two",
    },
    Code {
        code: "E1012",
        title: "gap bound not met",
        explanation: "`gap A with B at_least|at_most DIST` compares the least distance between the two boxes over\n\
the window with DIST. The report gives the least distance and when it occurred.\n
    gap amb with lead at_least 0.5 m",
    },
    Code {
        code: "E1013",
        title: "agent did not stop before the landmark",
        explanation: "`stopped A before LANDMARK` holds when A's speed falls below 0.1 m/s within the window and the\n\
front of its box never passes the landmark, measured along the lane A starts in. The report gives\n\
when the front passed it and how far, or A's lowest speed.\n
    stopped ego before stop_line during 0..5 s",
    },
    Code {
        code: "E1014",
        title: "agent did not reach the landmark",
        explanation:
            "`reach A LANDMARK by T s` holds when the front of A's box reaches the landmark, measured along the\n\
lane A starts in, within the window. The report says how far short it stayed.\n
    reach amb stop_line by 8 s",
    },
    Code {
        code: "E1015",
        title: "speed bound not met",
        explanation: "`speed A at_least|at_most SPEED` bounds A's speed over the window. The report gives the\n\
speed furthest beyond the bound and when.\n
    speed farm at_least 20 km/h
    speed ego at_most 2 km/h during 6.5..7 s",
    },
    Code {
        code: "E1020",
        title: "snapshot differs",
        explanation: "The run's snapshot (checked summary, verdicts, tracks at 1 Hz in centimetres, contacts,\n\
BEV and occupancy digests) differs from `snapshots/NAME.snap` beside the scenario. A diff is\n\
printed. If the change is meant, accept it:\n
    rocc test scenarios/ --review     // accept, reject or skip each change
    rocc test scenarios/ --accept     // accept all",
    },
    Code {
        code: "E1021",
        title: "snapshot missing",
        explanation: "A scenario has no `snapshots/NAME.snap` yet. `rocc test --accept` writes it; review and commit\n\
it with the scenario.\n
    rocc test scenarios/ --accept",
    },
    Code {
        code: "E1022",
        title: "not a rocc test snapshot",
        explanation: "`snapshots/NAME.snap` exists but is not a `rocc test` snapshot: no `---` header (insta's file\n\
format), a header whose `expression` is not `rocc test` (an insta snapshot of something else), or\n\
not UTF-8. rocc never overwrites it; move or delete it, then run `rocc test --accept`.\n
    rocc test scenarios/     // error: scenarios/snapshots/NAME.snap: no `---` header",
    },
    Code {
        code: "E1023",
        title: "nothing to test",
        explanation:
            "A path given to `rocc test` does not exist, or a folder holds no `.scn` file (subfolders are not\n\
searched: they hold kind files and snapshots).\n
    rocc test empty/     // error: the folder holds no .scn file",
    },
    Code {
        code: "E1024",
        title: "cannot write a test output",
        explanation:
            "A snapshot, pending `.snap.new` or `--junit` report could not be written (folder missing or not\n\
writable), or `--review` could not read an answer. Files are written to a temporary name and\n\
renamed, so no half file is left.\n
    rocc test scenarios/ --junit missing/dir/report.xml     // error: cannot write",
    },
];
