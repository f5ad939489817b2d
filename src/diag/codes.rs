//! Every diagnostic code rocc can emit, with the long explanation `rocc explain CODE` prints.
//! E00xx: files and syntax. E01xx: the checker. E02xx: road and placement. E04xx: I/O.
//! E07xx: import, edit and eval.
//! E06xx: the LLM front end (`rocc text`): the HTTP client, the model's replies, the repair loop.
//! E08xx: CIREN crash recreation (`rocc ciren`): E0800-E0849 records and SAFE extractions.
//! E0850-E0899: the CIREN VLM route (`rocc ciren extract`): case files, the conflict descriptor.
//! E09xx: the learned (grounded) occupancy backend and `rocc train`.
//! E10xx: expectations and `rocc test`.
//!
//! A `\` line continuation also eats the next line's leading spaces, so an indented example
//! line follows a literal line break (no `\n\` before it); a test guards this.

pub struct Code {
    pub code: &'static str,
    pub title: &'static str,
    pub explanation: &'static str,
}

pub const CODES: &[Code] = &[
    Code {
        code: "E0001",
        title: "syntax error",
        explanation: "The file does not follow the grammar of the `.scn` language. The error points at the\n\
first token the parser could not accept. When a block was left open, it points at the `{` that\n\
is never closed and shows where the next statement begins, or which `}` (indented for an\n\
enclosing block) was taken as the block's end.\n
    agent ego: sedan { at west.in[1], 20 m before center     // `}` missing here
    agent other: sedan { ... }\n\n\
Close every `{` with `}`. Statements are separated by newlines or `;`.",
    },
    Code {
        code: "E0002",
        title: "cannot read file",
        explanation: "A scenario or an imported file could not be read: it does not exist, is a directory,\n\
is not UTF-8 text, or is larger than the 4 MiB rocc accepts for one source file.\n
    use \"kinds/trucks.scn\"      // error when kinds/trucks.scn does not exist
    $ rocc check missing.scn     // error: cannot read `missing.scn`",
    },
    Code {
        code: "E0003",
        title: "import cycle",
        explanation: "`use` imports form a cycle: a file imports itself, directly or through others.\n
    // a.scn\n    use \"b.scn\"\n    // b.scn\n    use \"a.scn\"      // error: cycle a.scn -> b.scn -> a.scn\n\n\
Move the shared kinds into a third file that both import.",
    },
    Code {
        code: "E0004",
        title: "import escapes the project",
        explanation: "`use` paths are relative to the importing file and must stay inside the directory of\n\
the scenario being compiled: absolute paths and paths that climb out with `..` are rejected, so\n\
a scenario library can be moved and compiled anywhere.\n
    use \"kinds/trucks.scn\"      // fine\n    use \"/etc/kinds.scn\"        // error\n    use \"../../kinds.scn\"       // error",
    },
    Code {
        code: "E0005",
        title: "wrong items in a file",
        explanation: "A scenario file holds exactly one `scenario` block (plus `use` and `kind` items); an\n\
imported file holds only `kind` items and further `use` imports.\n
    // kinds.scn, imported with `use \"kinds.scn\"`
    kind forklift: vehicle { length 3 m; width 1.2 m; height 2.1 m }   // fine
    scenario s { ... }                                                        // error",
    },
    Code {
        code: "E0101",
        title: "unit of the wrong dimension",
        explanation: "Numbers carry units and each statement expects one dimension:
  length m, cm, km; speed m/s, km/h, mph; time s, ms; angle deg, rad; frequency Hz; ratio %.\n\
Bare numbers are counts.\n
    speed 5 m          // error: a speed needs m/s, km/h or mph\n    speed 5 m/s        // fine",
    },
    Code {
        code: "E0102",
        title: "missing unit",
        explanation: "A physical quantity was written without a unit. rocc never guesses units: write\n\
`20 m`, `30 km/h`, `4 s`.\n
    goal { speed 30 }        // error: 30 what?
    goal { speed 30 km/h }   // fine",
    },
    Code {
        code: "E0103",
        title: "value out of range",
        explanation: "A value is outside what rocc accepts for that statement: a negative speed or size, a\n\
duration over 120 s, a rate over 100 Hz, a lane count outside 1..=6, a density outside 0..1, a\n\
percentage outside 0..100 %. Some limits join parameters: a `curve` radius must exceed the\n\
road's half width (median / 2 + lanes x lane_width + shoulder, plus 3 m of sidewalk) by 5 m, and\n\
a `roundabout` radius must leave a central island of at least 3 m inside its ring.\n
    duration 300 s                                  // error: at most 120 s
    road straight { lanes 8 }                       // error: 1..=6 lanes
    road curve { radius 20 m; lanes 6; lane_width 6 m; median 20 m }   // error: radius 51 m or more",
    },
    Code {
        code: "E0104",
        title: "empty or reversed range",
        explanation: "A range `a..b` samples uniformly in [a, b]; it needs a <= b.\n
    length 4.9..4.4 m     // error\n    length 4.4..4.9 m     // fine",
    },
    Code {
        code: "E0105",
        title: "duplicate statement",
        explanation: "A block states the same property twice (two `speed`s, two `road`s, two agents of\n\
the same name). Keep one; both places are shown.\n
    agent a: sedan { at west.in[1], 20 m before center }
    agent a: suv { at west.in[2], 10 m before center }   // error: `a` again",
    },
    Code {
        code: "E0106",
        title: "missing statement",
        explanation: "Something required is missing: a scenario needs `duration` and `road`; an agent or\n\
object needs a placement `at ...` (or a replayed `track`); a conflict needs `at_fault`, `struck`,\n\
`impact` and `point`.\n
    scenario s { road straight }                    // error: no `duration`
    agent ego: sedan { goal { speed 30 km/h } }     // error: no `at ...`",
    },
    Code {
        code: "E0107",
        title: "unknown agent",
        explanation: "A statement names an agent that the scenario does not declare. Agent names are used by\n\
`egos [...]`, `stop behind NAME`, `lateral away_from NAME` and `conflict` fields.\n
    agent front: sedan { at south.in[1], 2 m before stop_line }
    agent ego: sedan { at south.in[1], 12 m before stop_line; goal { stop behind frnt } }
                                                                  // error: did you mean `front`?",
    },
    Code {
        code: "E0108",
        title: "unknown kind",
        explanation: "`agent NAME: KIND` names a kind that neither the stdlib prelude (`stdlib/kinds.scn`)\n\
nor a `use`d file defines. Define new kinds in a kind file:\n
    kind tractor: vehicle { length 3.5..4.5 m; width 2.0..2.4 m; height 2.5..3.0 m }",
    },
    Code {
        code: "E0109",
        title: "unknown road template",
        explanation: "`road TEMPLATE` must be one of straight, curve, four_way, t_junction, merge, roundabout.\n
    road crossroads { lanes 2 }    // error: not a template
    road four_way { lanes 2 }      // fine",
    },
    Code {
        code: "E0110",
        title: "unknown or inapplicable parameter",
        explanation: "A `road` or `traffic` block sets a parameter that does not exist or does not apply to\n\
the template (`radius` on a straight road). Road parameters: lanes, lane_width, speed_limit,\n\
shoulder, median, crosswalks (not on merge, which has no crossing), sidewalks, length, and\n\
radius/angle on curve, radius on roundabout.\n\
Traffic parameters: density, randomness.\n
    road straight { lanes 1; radius 50 m }   // error: a straight road has no radius
    road merge { crosswalks on }             // error: a merge has no crosswalk
    traffic { density 0.5; speed 30 km/h }   // error: unknown traffic parameter",
    },
    Code {
        code: "E0111",
        title: "unknown road arm or landmark",
        explanation: "A placement names an arm the template does not have (`north` on a straight road) or a\n\
landmark that does not exist there: `stop_line` and `junction` exist on junction templates only\n\
(four_way, t_junction, roundabout, merge); `center` exists everywhere.\n
  straight, curve: west, east\n  four_way, roundabout: north, east, south, west
  t_junction: west, east, south\n  merge: main, ramp\n
    road straight { lanes 2 }
    agent ego: sedan { at north.in[1], 20 m before center }      // error: no arm `north`
    agent ego: sedan { at west.in[1], 20 m before stop_line }    // error: no stop lines",
    },
    Code {
        code: "E0112",
        title: "lane index out of range",
        explanation: "`ARM.in[k]` and `ARM.out[k]` count lanes from 1 (nearest the centre line) to the road's\n\
`lanes` per direction.\n
    road straight { lanes 2 }\n    agent ego: sedan { at west.in[3], 20 m before center }   // error: 2 lanes",
    },
    Code {
        code: "E0113",
        title: "goal not valid for this agent",
        explanation: "Goals depend on how a kind moves. Static kinds (cones, barriers, signs, structures)\n\
have no goal and no speed. Pedestrians and animals walk: they may `cross`, keep a speed and stop,\n\
but cannot change lane, pull to the shoulder or turn. Vehicles cannot `cross`. A goal that\n\
cannot be met from the placement is rejected too: `stop at stop_line` or `turn` from an\n\
out-lane, or on a road without a junction.\n
    object c: traffic_cone { at west.in[1], 10 m before center; goal { speed 5 km/h } }  // error
    road straight { lanes 2; sidewalks on }
    agent p: pedestrian { at sidewalk(west.in), 5 m before center; goal { lateral change_lane left } }  // error
    agent p: pedestrian { at sidewalk(west.in), 5 m before center; goal { speed 1.4 m/s; lateral cross } }  // fine",
    },
    Code {
        code: "E0114",
        title: "invalid conflict",
        explanation: "A `conflict` stages a crash between two different agents. `at_fault` must be a mover;\n\
`impact` is one of rear_end, head_on, angle, sideswipe, pedestrian, object; `point` is a side of\n\
the struck agent: front, rear, left, right, front_left, front_right, rear_left, rear_right.\n\
`impact pedestrian` needs a pedestrian as `struck`, `impact object` a static one.\n
    conflict { at_fault v1; struck v2; impact sideswipe; point right; at 3 s }",
    },
    Code {
        code: "E0115",
        title: "invalid ego",
        explanation: "`egos [a, b]` lists agents whose viewpoint gets a clip; each must be a mover (a vehicle,\n\
bicycle, pedestrian or animal), not a static object. `egos vehicles` takes every vehicle.\n
    object c: traffic_cone { at west.in[1], 10 m before center }
    egos [c]        // error: a cone has no viewpoint to drive from",
    },
    Code {
        code: "E0116",
        title: "unknown word",
        explanation: "A closed vocabulary got a word it does not contain: a lateral goal (hold_lane,\n\
change_lane left|right, pull_to_shoulder, away_from NAME, cross), a turn (left, right, straight,\n\
u_turn), a side (left, right), a landmark (center, junction, stop_line), a class or motion in a\n\
kind definition.\n
    goal { lateral change_lane lft }     // error: did you mean `left`?
    goal { turn leftt }                  // error: did you mean `left`?",
    },
    Code {
        code: "E0117",
        title: "invalid track",
        explanation: "A `track` replays keyframes `TIME: (X, Y) yaw ANGLE` in the world frame or\n\
`TIME: LANE, DIST before|after LANDMARK` in lane coordinates (one value each, not a range). Times\n\
must strictly increase and start at or after 0 s; an agent with a track has no `at` and no goal.\n
    agent v: sedan {
        track { 0 s: (0 m, 0 m) yaw 0 deg; 1 s: (10 m, 0 m) yaw 0 deg }   // fine
    }
    agent w: sedan {
        track { 1 s: (0 m, 0 m) yaw 0 deg; 0.5 s: (5 m, 0 m) yaw 0 deg } // error: time goes back
    }",
    },
    Code {
        code: "E0118",
        title: "invalid row",
        explanation: "`row KIND from PLACE to PLACE every DIST` lines up static objects. Both ends must use\n\
the same placement form: lanes of one arm and direction (a row from one lane to another is a\n\
taper, its objects sliding across from the first lane's centre to the second's), one sidewalk,\n\
or world coordinates. The spacing must be positive, and a row may hold at most 500 objects.\n
    row traffic_cone from east.in[2], 20 m before center to east.in[1], 40 m before center every 4 m   // fine: a taper
    row traffic_cone from west.in[2], 20 m before center to east.out[2], 30 m after center every 5 m   // error: two arms
    row traffic_cone from west.in[1], 20 m before center to west.out[1], 30 m after center every 5 m   // error: two directions",
    },
    Code {
        code: "E0119",
        title: "kinds of different classes in one_of",
        explanation: "`one_of [a, b]` picks a kind with the seed; all choices must map to the same class and\n\
motion so that the rest of the agent (its goal, its placement) stays valid whatever is picked.\n
    agent a: one_of [sedan, pedestrian] { ... }   // error: vehicle and pedestrian
    agent a: one_of [sedan, suv, van] { ... }     // fine: all vehicles",
    },
    Code {
        code: "E0120",
        title: "impact type and point contradict each other",
        explanation: "`point` is the side of the struck agent that the crash hits, and the impact type says\n\
how the two meet, so not every pair fits. The at-fault agent strikes with its front in a rear-end,\n\
a head-on and an angle crash, and with its side in a sideswipe. The table (struck agent's sides\n\
as `point` names them):\n
    impact rear_end     point rear | rear_left | rear_right
    impact head_on      point front | front_left | front_right
    impact angle        point left | right | front_left | front_right | rear_left | rear_right
    impact sideswipe    point left | right | front_left | front_right | rear_left | rear_right
    impact pedestrian   any point
    impact object       any point\n
A front-to-front contact is a head-on, a front-to-rear one a rear-end; an angle or a sideswipe\n\
reaches a side or a corner, never the middle of the front or rear face.\n
    conflict { at_fault a; struck b; impact rear_end; point front }   // error: a rear-end hits the rear
    conflict { at_fault a; struck b; impact rear_end; point rear }    // fine",
    },
    Code {
        code: "E0121",
        title: "agent strikes twice",
        explanation: "An at-fault agent leaves its goal for one staged approach to the agent it strikes, so an\n\
agent is `at_fault` in one conflict only; it may be struck in any number of others (a pile-up).\n\
Both blocks are shown.\n
    conflict { at_fault a; struck b; impact rear_end; point rear; at 2 s }
    conflict { at_fault a; struck c; impact angle; point left; at 4 s }     // error: `a` strikes twice\n\n\
Keep one strike per agent, or let another agent strike.",
    },
    Code {
        code: "E0122",
        title: "crashes in an order that cannot happen",
        explanation: "A crash holds its pair from the contact on (motion after an impact is not simulated), so\n\
an agent that is struck stands still from then on and cannot strike anyone later. An agent's\n\
own strike comes before, or at the same time as, every crash that strikes it. A chain is\n\
written front first: the middle car strikes the car ahead, then the one behind strikes it.\n
    conflict { at_fault mid; struck lead; impact rear_end; point rear; at 2 s }
    conflict { at_fault tail; struck mid; impact rear_end; point rear; at 3 s }   // fine: a chain
    conflict { at_fault tail; struck mid; impact rear_end; point rear; at 2 s }
    conflict { at_fault mid; struck lead; impact rear_end; point rear; at 3 s }   // error: `mid` is struck first",
    },
    Code {
        code: "E0123",
        title: "a pair that crashes twice",
        explanation: "A crash holds its pair from the contact on, so two agents touch once: a second conflict\n\
between the same two (either way round) is refused, and both blocks are shown.\n
    conflict { at_fault a; struck b; impact rear_end; point rear; at 2 s }
    conflict { at_fault b; struck a; impact angle; point left; at 4 s }     // error: the same pair",
    },
    // ---- postures and track feasibility (E0130-E0134) ----
    Code {
        code: "E0130",
        title: "posture of a thing that has none",
        explanation: "`posture standing | kneeling | lying` sets the box of a person or an animal: lying, it is\n\
as long as the body is tall and 0.3 m high (an adult: about 1.8 x 0.6 x 0.3 m); kneeling, half\n\
its standing height. Only pedestrians and walking kinds (animals) have a posture.\n
    object injured: adult { at west.in[1], 5 m before center; posture lying }   // fine
    object wreck: sedan { at west.in[1], 5 m before center; posture lying }     // error\n\n\
Give a vehicle or an object another box with `length`, `width` and `height`.",
    },
    Code {
        code: "E0131",
        title: "track too fast",
        explanation: "Between two keyframes of a `track` the body would move faster than its kind can: 324 km/h\n\
for vehicles, 30 m/s for bicycles and scooters, 12 m/s for people, 25 m/s for animals (plus\n\
0.3 m of recording jitter per step). The error names the keyframe with the speed and the limit.\n
    agent v: sedan { track { 0 s: (0 m, 0 m) yaw 0 deg; 1 s: (120 m, 0 m) yaw 0 deg } }   // error: 120 m/s",
    },
    Code {
        code: "E0132",
        title: "track accelerates too hard",
        explanation: "The mean velocity of a `track` changes faster than its kind's grip allows: 12 m/s2 for\n\
vehicles, 8 for bicycles and people, 15 for animals, braking and cornering included. Velocities\n\
are averaged over at least 0.5 s so recording jitter does not count.\n
    agent v: sedan { track { 0 s: (0 m, 0 m) yaw 0 deg; 1 s: (10 m, 0 m) yaw 0 deg; 2 s: (50 m, 0 m) yaw 0 deg } }   // error: 30 m/s2",
    },
    Code {
        code: "E0133",
        title: "track turns too fast",
        explanation: "The heading of a `track` turns faster than its kind can. A vehicle turns only while it\n\
moves, no tighter than its turning radius (0.6 of its length) and no faster than its grip allows\n\
at that speed; people and animals turn at most a full turn a second. 10 degrees of recording\n\
jitter per step are allowed.\n
    agent v: sedan { track { 0 s: (0 m, 0 m) yaw 0 deg; 1 s: (1 m, 0 m) yaw 90 deg } }   // error: turns on the spot",
    },
    Code {
        code: "E0134",
        title: "vehicle track slips sideways",
        explanation: "A vehicle or bicycle moves along its heading, forwards or in reverse: between two\n\
keyframes the direction of travel may differ from the mean heading by at most 30 degrees (plus\n\
0.3 m of recording jitter).\n
    agent v: sedan { track { 0 s: (0 m, 0 m) yaw 0 deg; 1 s: (0 m, 20 m) yaw 0 deg } }   // error: 90 degrees off its heading\n\n\
Give each keyframe the heading of the travel, or check that x and y are not swapped.",
    },
    // ---- triggers and behaviour (E0150-E0169) ----
    Code {
        code: "E0150",
        title: "unknown or malformed trigger condition",
        explanation: "`start when NAME CONDITION` starts a goal when a condition on agent NAME holds. The\n\
conditions are `within DIST` (centre distance), `ttc under TIME` (time to collision),\n\
`headway under TIME` (NAME's time to reach this agent), `reaches stop_line` or `reaches kerb`,\n\
and `starts` (NAME's own goal has started). Each takes what it names, nothing else.\n
    goal { lateral cross; start when ego within 20 m }     // fine
    goal { lateral cross; start when ego wihtin 20 m }     // error: unknown condition
    goal { lateral cross; start when ego within }          // error: `within` takes a distance",
    },
    Code {
        code: "E0151",
        title: "trigger cycle",
        explanation: "Triggers that wait on each other in a cycle (a starts when b starts, b starts when a\n\
starts; or an agent that waits for itself) have no first cause: which starts first would\n\
depend on itself. Every agent of the cycle is labelled.\n
    agent a: sedan { at west.in[1], 30 m before center; goal { speed 10 m/s; start when b starts } }
    agent b: sedan { at east.in[1], 30 m before center; goal { speed 10 m/s; start when a starts } }   // error\n\n\
Let one of them start on time (`start after 2 s`) or on a third agent.",
    },
    Code {
        code: "E0152",
        title: "unknown behaviour setting",
        explanation: "`behaviour { ... }` sets how attentive and law-abiding an agent is: `yield always|never`,\n\
`stop_line obey|ignore`, `reaction TIME` (0..5 s) and `speeding PERCENT` (0..200 %). Each is\n\
given once; anything else is refused with the nearest name.\n
    behaviour { yield never; reaction 1.5 s }     // fine
    behaviour { yeild never }                     // error: unknown setting
    behaviour { yield sometimes }                 // error: `yield` takes `always` or `never`",
    },
    Code {
        code: "E0153",
        title: "behaviour contradicts the agent",
        explanation: "A behaviour setting must fit the agent that carries it: static things have no behaviour,\n\
walkers have no stop line to ignore and no speed limit to exceed, and an agent told to\n\
`stop at stop_line` cannot also ignore it.\n
    agent kid: child { at sidewalk(east.out), 10 m after center
                       goal { lateral cross }; behaviour { yield never } }       // fine: darts out
    agent car: sedan { at south.in[1], 20 m before stop_line
                       goal { stop at stop_line }; behaviour { stop_line ignore } }   // error",
    },
    Code {
        code: "E0154",
        title: "trigger that cannot happen",
        explanation: "A trigger must watch something that can happen: `headway` and `starts` need an agent that\n\
moves, `reaches stop_line` a vehicle placed on an in-lane of a road with stop lines, and\n\
`reaches kerb` a walker with `lateral cross`.\n
    goal { speed 8 m/s; start when kid reaches kerb }    // fine when `kid` crosses
    goal { speed 8 m/s; start when cone starts }         // error: a cone never moves",
    },
    Code {
        code: "E0155",
        title: "invalid goal phase",
        explanation: "A later `goal` block of an agent is a phase: it takes over from the goal before it once its\n\
`start` holds (`start after T` counts from the clip's start, `start when ...` is a trigger),\n\
and only after that goal has started. A phase gives one `speed` and one `start`, nothing else:\n\
turns, lateral moves and stops belong to the first goal block. Static things and replayed\n\
tracks have no phases.\n
    goal { speed 10 m/s }
    goal { speed 0 m/s; start when car headway under 1.5 s }     // fine: brakes to a stop
    goal { speed 4 m/s; turn left; start after 1 s }             // error: a turn in a phase",
    },
    // ---- near misses (E0190-E0195) ----
    Code {
        code: "E0190",
        title: "near-miss gap out of range",
        explanation: "`gap` is the least distance between the two boxes as the passer goes by, 0.2..3 m.\n\
Closer than 0.2 m is contact within the boxes' tolerance (stage a `conflict`); farther than\n\
3 m is not a near miss.\n
    near_miss { passer a; passed b; gap 0.5 m; at 4 s }     // fine
    near_miss { passer a; passed b; gap -0.5 m }            // error: below 0
    near_miss { passer a; passed b; gap 50 m }              // error: not near",
    },
    Code {
        code: "E0191",
        title: "near miss without a pair that can pass",
        explanation: "A near miss names two different agents, and its passer steers to pass: it moves and\n\
follows a goal (not static, not a recorded `track`). The passed agent may be anything.\n
    near_miss { passer a; passed a; gap 0.5 m }              // error: one agent
    near_miss { passer cone; passed a; gap 0.5 m }           // error: `cone` is static",
    },
    Code {
        code: "E0192",
        title: "near-miss field of the wrong kind",
        explanation: "`passer` and `passed` take agent names, `side` takes `left` or `right` (the side of the\n\
passed agent the passer goes by; without it, the side the passer starts on), `gap` a length and\n\
`at` a time within the clip (half the clip without it).\n
    near_miss { passer a; passed b; gap 0.5 m; side left; at 4 s }   // fine
    near_miss { passer a; passed b; gap 0.5 m; side front }          // error: not a side",
    },
    Code {
        code: "E0193",
        title: "a pair that crashes and misses at the same time",
        explanation: "A near miss has no contact; a `conflict` of the same two agents within 1.5 s of it is a\n\
contradiction. Both blocks are shown.\n
    conflict { at_fault a; struck b; impact sideswipe; point left; at 4 s }
    near_miss { passer a; passed b; gap 0.5 m; at 4 s }      // error: same pair, same time",
    },
    Code {
        code: "E0194",
        title: "passer already staged",
        explanation: "A near miss is staged like a crash: its passer leaves its goal for one planned approach.\n\
A passer that is in a conflict, or passes in another near miss, cannot follow two; stage the\n\
second with another agent.\n
    near_miss { passer a; passed b; gap 0.5 m; at 2 s }
    near_miss { passer a; passed c; gap 0.5 m; at 5 s }      // error: `a` passes twice",
    },
    Code {
        code: "E0195",
        title: "near miss cannot be staged",
        explanation: "The passer comes alongside the passed agent, parallel, its box `gap` from the stated side,\n\
at the stated time, then returns to its route. The rolled-out boxes are measured: the least\n\
gap over the clip may be at most 0.15 m below `gap` and never contact, and within 0.5 s of `at`\n\
the two must come within `gap` + 0.15 m. Otherwise the scene is refused, saying what happened:\n\
the passer cannot reach the passed agent in time within its limits, or they touch, or they\n\
pass too close or too far. Start them closer, give them speeds that bring them level, pick the\n\
other `side`, or move `at`.\n
    // v1 in the outer lane, v2 in the inner one: v1 would cut across v2 to reach its far side
    near_miss { passer v1; passed v2; gap 0.4 m; side left; at 3 s }    // error: they touch
    near_miss { passer v1; passed v2; gap 0.4 m; side right; at 3 s }   // fine",
    },
    Code {
        code: "E0170",
        title: "siren on a kind without one",
        explanation: "`siren on` and `siren off` are for emergency vehicles: `ambulance`, `fire_truck`,\n\
`police_car` and kinds derived from them, whose siren is on unless stated. With it on, cross\n\
traffic holds for them at junctions and vehicles ahead pull over; `siren off` makes one an\n\
ordinary vehicle. Any other kind has no siren.\n
    agent amb: ambulance { at west.in[1], 60 m before center; speed 50 km/h; siren off }  // fine
    agent car: sedan { at west.in[1], 20 m before center; siren on }  // error
    kind my_amb: ambulance { length 7.0 m }   // derived: `siren off` is fine on it",
    },
    Code {
        code: "E0201",
        title: "placement off a valid surface",
        explanation: "Each class starts where it can physically be: moving vehicles on lanes, shoulders or\n\
the junction; moving bicycles also on sidewalks and crosswalks; people, animals and static things\n\
of any class (cones, debris, a wreck) anywhere on the map or within 10 m of it, lanes included.\n
    agent ego: sedan { at sidewalk(east.out), 10 m after center }   // error
    object injured: adult { at west.in[1], 5 m before center; posture lying }   // fine
    object c: traffic_cone { at (500 m, 500 m) }                    // error: far off the map",
    },
    Code {
        code: "E0202",
        title: "initial boxes overlap",
        explanation: "Two agents' boxes overlap at their initial placement. Both are named with their spans;\n\
move one further along the lane, to another lane, or shorten the boxes.\n
    agent a: sedan { at west.in[1], 20 m before center }
    agent b: sedan { at west.in[1], 22 m before center }   // error: a sedan is ~4.7 m long
    agent b: sedan { at west.in[1], 30 m before center }   // fine",
    },
    Code {
        code: "E0203",
        title: "placement off the road",
        explanation: "A lane-relative placement lies beyond the end of the lane (the road is `length` long;\n\
default 120 m, junction arms 60 m), or a crosswalk/sidewalk named by the placement does not\n\
exist because `crosswalks`/`sidewalks` is off.\n
    road straight { lanes 1 }                                     // 120 m: 60 m each side
    agent ego: sedan { at west.in[1], 70 m before center }        // error: lane ends 60 m before
    agent p: pedestrian { at crosswalk(west), 50 % }              // error: `crosswalks` is off",
    },
    Code {
        code: "E0204",
        title: "goal cannot be met on this map",
        explanation: "An agent's goal asks for something the road does not offer from where the agent starts:\n\
a `turn` where its lane has no junction connector of that kind, a `change_lane` toward a lane\n\
that does not exist, `stop at stop_line` on a lane with no stop line ahead, `cross` with no\n\
road nearby to cross, a turn whose junction path is more than 3 times tighter than the\n\
kind's turning radius (derived from its length: a bus turns on about 10 m), or a turn that,\n\
driven on that radius, puts a wheel more than 0.25 m off the drivable surface (a sedan's\n\
U-turn on a one-lane four_way; overhangs beyond the axles may sweep over the kerb).\n
    road straight { lanes 1 }\n    agent ego: sedan { at west.in[1], 20 m before center; goal { turn left } }   // error\n\n\
Place the agent on a lane that reaches a junction offering the turn, or change the goal.",
    },
    Code {
        code: "E0205",
        title: "conflict makes no contact near its time, or not as asked",
        explanation: "A `conflict` is staged by steering the at-fault agent, within its motion limits, into\n\
the struck agent so that they touch within 1.5 s of `at` (mid-clip without `at`). When the two\n\
are too far apart for that, or their motion keeps them apart, the crash would be silently missing\n\
from the clip; instead `rocc check` and `rocc compile` report it at the conflict. The same goes\n\
for a crash that happens but not as written: the contact must lie on the struck agent's `point`\n\
side (the thirds of each face of its box; any face of a struck object) and on the at-fault\n\
agent's striking face (its front, or its side for a `sideswipe`), at least 5 cm deep: a\n\
`rear_end` on `rear` that the struck car, its way blocked by the striker, drives into front\n\
first is refused, not labelled a rear-end, and so is a 3 mm graze. A staging that fails is\n\
planned again with its impact away from the times already tried, up to three times, before\n\
this error, which then says what the first plan (nearest `at`) did. The at-fault agent is\n\
reckless toward the struck agent only: it slows for any other agent in its way (a walker on\n\
the course it would brake on, a car whose stopping distance it would cut into, a car coming\n\
the other way), and when that makes it miss, the help names the agent that held it back\n\
longest. Nor may a staging have one of the pair stopped dead, beyond its braking, short of\n\
another agent (by the last-resort overlap guard): when the first plan does and no plan tried\n\
does better, it is refused, naming the agent it would have run into. Nor may it make anyone\n\
brake beyond their limit (8 m/s2 for a car) within 1 m of the striker: a striker cutting across\n\
a lane a few metres ahead of a car, or turning back across the lane of one coming the other\n\
way, leaves it no room its brakes could stop it in. Other agents brake for where a striker\n\
will stand (its contact pose, where the crash stops it dead), not only for where it is; when\n\
that is not enough under any plan tried, the error names who would have to brake, how hard,\n\
and for whom.\n
    agent a: sedan { at west.in[1], 50 m before center; speed 30 km/h }
    agent b: sedan { at west.in[1], 50 m after center; speed 30 km/h }
    conflict { at_fault a; struck b; impact rear_end; point rear; at 0.5 s }   // error: 100 m apart\n\n\
Start the pair closer, give them speeds that bring them together by then, or move `at` later.",
    },
    Code {
        code: "E0206",
        title: "`stop behind` names an agent that is not ahead",
        explanation: "`stop behind NAME` queues behind a leader, so NAME must be ahead of the agent on its route\n\
(its lane, or the lane its `change_lane` moves it to, continued through the junction by its\n\
`turn`, or straight on; an agent off the lanes goes along its heading). Judged on the placed poses, NAME qualifies when its centre is further\n\
along that route and either inside the route's corridor (half the lane width plus half its own\n\
width: a cyclist at the lane edge counts, a car in the next lane does not), or it will enter the\n\
corridor ahead: a walker or animal with `lateral cross`, a vehicle with `change_lane` toward it,\n\
or a vehicle whose own route merges into it heading the same way (a ramp, a turn into the exit\n\
lane). A leader behind the agent, or on another road or lane with no such relation, would be\n\
ignored by the controller, so it is an error. A replayed track is not judged.\n
    agent a: sedan { at west.in[1], 30 m before center; goal { stop behind b } }
    agent b: sedan { at west.in[1], 50 m before center }     // error: b is behind a
    agent b: sedan { at east.in[1], 10 m before center }     // error: the other direction
    agent b: sedan { at west.in[1], 10 m before center }     // fine: ahead on a's lane",
    },
    Code {
        code: "E0207",
        title: "two vehicles placed with no order to cross",
        explanation: "Vehicles whose junction paths cross take turns: one holds short of the stretch the two\n\
paths share while the other crosses. Two placed so near that stretch, and so fast, that neither can\n\
stop short of it within emergency braking (8 m/s2 for a car or bus) are judged at the start on\n\
their boxes, laid along their paths as they steer through the junction: if one can give way,\n\
braking that hard while the other goes on at its placed speed (or slowed to a quarter, half or\n\
three quarters of it), without the boxes meeting, it does so. If neither can, and braking both\n\
they still meet, or stop each in the other's way, no order keeps them apart, and `rocc check`\n\
reports both, with when each would be struck. A vehicle with `start after`, or one whose stop\n\
goal lies short of the stretch, can hold and is not judged; nor is a conflict pair.\n
    road four_way { lanes 1; speed_limit 50 km/h }
    agent a: sedan { at south.in[1], 5 m before stop_line; speed 14 m/s; goal { turn straight } }
    agent b: sedan { at west.in[1], 2 m before stop_line; speed 14 m/s; goal { turn straight } }   // error
    agent a: sedan { at south.in[1], 25 m before stop_line; speed 14 m/s; goal { turn straight } } // fine\n\n\
Start one further back or slower, or delay it with `start after`. To stage the crash the two are\n\
headed for, write a `conflict`.",
    },
    // ---- track keyframes on the map (E0210) ----
    Code {
        code: "E0210",
        title: "vehicle track off the road",
        explanation: "A moving vehicle's `track` keyframe lies where it cannot drive: not on a lane, the shoulder\n\
or the junction (a sidewalk, the median, off the road). A scene on `road none` (recorded tracks\n\
imported with `rocc import boxes`) has no map to check against.\n
    road straight { lanes 1; sidewalks on }
    agent v: sedan { track { 0 s: (-20 m, -1.75 m) yaw 0 deg; 1 s: (-10 m, -6 m) yaw 0 deg } }   // error: on a sidewalk",
    },
    // ---- traffic signals (E0230) ----
    Code {
        code: "E0230",
        title: "signals on a road without a signalled junction",
        explanation: "Traffic signals stand at a junction whose approaches have stop lines: `four_way` and\n\
`t_junction`. A straight road, a curve, a merge or a roundabout has no such junction, so\n\
`signals on` there would hold nobody and is refused.\n
    road four_way { signals on }      // fine
    road straight { signals on }      // error",
    },
    Code {
        code: "E0231",
        title: "a signal cycle that cannot run",
        explanation: "A signal cycle's times (`signal_green`, `signal_yellow`, `signal_all_red`,\n\
`signal_offset`) are single times within 0..600 s, and green must be longer than 0 s: a cycle\n\
with no green keeps every approach red forever.\n
    road four_way { signals on; signal_green 25 s; signal_yellow 4 s }   // fine
    road four_way { signals on; signal_green 0 s }                       // error: red forever
    road four_way { signals on; signal_yellow -3 s }                     // error: negative",
    },
    Code {
        code: "E0232",
        title: "a signal cycle without signals",
        explanation: "`signal_green`, `signal_yellow`, `signal_all_red` and `signal_offset` time the signals\n\
that `signals on` puts up; without it they time nothing.\n
    road four_way { signals on; signal_green 30 s }   // fine
    road four_way { signal_green 30 s }               // error",
    },
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
crosswalks, pedestrians on walkways, crosswalks or the shoulder; static objects anywhere in the\n\
100 m grid. The check is at the box centre, in every edited frame.\n
    $ rocc edit out/cut_in/ego --insert pedestrian at 10,0   // error: a pedestrian in the middle of the lane",
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
    Code {
        code: "E0601",
        title: "LLM endpoint unreachable",
        explanation: "`rocc text` could not connect to the model server: nothing listens at the address, the\n\
host name does not resolve, or the connection was reset. Start the server first and pass its\n\
OpenAI-compatible base URL:\n
    rocc text \"...\" -o scene.scn --server llamacpp --endpoint http://127.0.0.1:8080/v1\n\n\
The endpoint may also come from ROCC_LLM_ENDPOINT. docs/llm.md has the server commands.",
    },
    Code {
        code: "E0602",
        title: "LLM request timed out",
        explanation: "The model server accepted the request but did not answer within `--timeout` seconds\n\
(default 120). Long grammar-constrained generations on a CPU can be slow: raise `--timeout`, lower\n\
`--max-tokens`, or use a smaller model. Timeouts are not retried: the server is probably busy.\n
    $ rocc text \"a deer crosses at dusk\" -o deer.scn --timeout 600   // give a slow CPU server more time",
    },
    Code {
        code: "E0603",
        title: "LLM server returned an HTTP error",
        explanation: "The server answered with an error status (or a JSON `error` object). 429 and 5xx are\n\
retried `--retries` times with exponential backoff (honouring `Retry-After`) before this error;\n\
other statuses are reported at once. 401/403: pass `--api-key` or set ROCC_LLM_API_KEY. 404:\n\
the endpoint should end in `/v1` and the model name must exist on the server. 400: the server\n\
rejected the request body; if it names `grammar` or `structured_outputs`, the server does not\n\
support grammar-constrained decoding in that form: pick the right `--server` or pass\n\
`--no-grammar`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint https://api.example.com/v1   // error: 401 Unauthorized
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint https://api.example.com/v1 --api-key $KEY   // fine",
    },
    Code {
        code: "E0604",
        title: "LLM reply is not a chat completion",
        explanation: "The server's reply is not JSON, or is JSON without the OpenAI chat-completion shape\n\
(`choices[0].message.content`). The endpoint is probably not an OpenAI-compatible\n\
`/v1/chat/completions` (a web page, a proxy error, another API). Check `--endpoint`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint http://127.0.0.1:8080   // error if that serves a web page
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint http://127.0.0.1:8080/v1   // fine",
    },
    Code {
        code: "E0605",
        title: "LLM reply is empty",
        explanation: "The reply has no choices, or the message content is empty or null. Some servers do this\n\
when the prompt exceeds the context window or when a grammar admits no continuation. Use a model\n\
with a larger context, or look at the exchange with `--transcript`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --transcript   // saves every request and reply beside the output",
    },
    Code {
        code: "E0606",
        title: "LLM reply truncated",
        explanation: "The model stopped because it hit `--max-tokens` (`finish_reason: length`), so its text is\n\
incomplete. Raise `--max-tokens`; a model that keeps generating whitespace or comments under a\n\
grammar constraint is a sign the model is too small for the task.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --max-tokens 4096   // room for the whole scenario",
    },
    Code {
        code: "E0607",
        title: "LLM refused",
        explanation: "The model refused the request (an OpenAI `refusal` field, or `finish_reason:\n\
content_filter`). Rephrase the sentence; scenario descriptions of crashes and emergencies are\n\
ordinary traffic-safety engineering, which saying so in the sentence often helps with.\n
    $ rocc text \"a van cuts in front of the ego, for a safety test\" -o cut_in.scn",
    },
    Code {
        code: "E0608",
        title: "LLM reply is not UTF-8",
        explanation: "The reply body is not valid UTF-8 text. rocc reads replies as JSON, which is UTF-8 by\n\
definition; the server or a proxy in between is misconfigured.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn   // error if a proxy answers in Latin-1",
    },
    Code {
        code: "E0609",
        title: "LLM reply too long",
        explanation: "The reply body is over 4 MiB or the message content over 64 KiB: far more than any scenario\n\
needs. rocc stops reading rather than buffer a runaway generation; lower `--max-tokens`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --max-tokens 2048   // bound the generation",
    },
    Code {
        code: "E0610",
        title: "LLM reply is not a scenario",
        explanation: "The model answered with text that holds no `scenario NAME { ... }` block (prose, an\n\
apology, another language). In the repair loop this counts as a failed attempt: the diagnostic is\n\
sent back and the model is asked again, up to `--max-repairs` times. Grammar-constrained decoding\n\
(`--server vllm` or `llamacpp`) makes this impossible.\n
    I'm sorry, I can only describe scenes in English.   // error: no `scenario` block in the reply",
    },
    Code {
        code: "E0611",
        title: "LLM did not produce a usable scene schema",
        explanation: "The schema stage asks for one JSON object (road template, agents with kinds and\n\
placements, a brief). The reply was not such an object after `--max-repairs` corrections: not\n\
JSON, missing fields, or values of the wrong type. The last reply and the parse error are shown;\n\
`--transcript` keeps the whole exchange.\n
    { \"road\": \"four_way\", \"agents\": \"two cars\" }   // error: `agents` must be an array",
    },
    Code {
        code: "E0612",
        title: "LLM goal reply unusable",
        explanation: "The goal stage (\"traffic director\") asks for `goal { ... }` blocks in the goal\n\
vocabulary. A reply without a block that parses, or naming agents that do not exist, is corrected\n\
up to `--max-repairs` times; after that the agent keeps its initial speed and no goal (a warning)\n\
and the checker has the last word on the emitted file.\n
    goal { cutter: change_lane left }   // fine, when the scene declares `cutter`
    goal { truck: stop }                // error if the scene has no agent `truck`",
    },
    Code {
        code: "E0613",
        title: "generated scenario still fails to check",
        explanation: "The emitted `.scn` did not check (syntax, names, units, placement or rollout) and\n\
`--max-repairs` rounds of sending the diagnostics back did not fix it. Nothing is written to\n\
`-o`; the last attempt is kept beside it as `NAME.rejected.scn` with its diagnostics, so it can be\n\
fixed by hand (`rocc check NAME.rejected.scn`) or the run repeated with a stronger model.\n
    $ rocc check cut_in.rejected.scn   // the last attempt, with its diagnostics",
    },
    Code {
        code: "E0614",
        title: "bad `rocc text` option",
        explanation: "An option of `rocc text` is unusable: the endpoint is not an http(s) URL (https needs the\n\
`https` build feature), `--model` is missing for a server that needs one, `--density` or\n\
`--randomness` is outside 0..1, the `--image` file cannot be read or is not PNG/JPEG/WebP/GIF, or\n\
the sentence is empty.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --density 1.5   // error: --density must be in 0..1",
    },
    Code {
        code: "E0800",
        title: "cannot read CIREN case",
        explanation: "A `rocc ciren` input could not be read: the path does not exist, a directory holds no
`crash_report.xml` (in it or one level down), the file is larger than the cap (16 MiB for a
case record, 1 MiB for a SAFE extraction; the size is checked before reading), or it is not
UTF-8 text. Nothing is written for that input; the other inputs of the batch go on and the
exit status is 1.

    rocc ciren import ciren/100237 -o scn/       # a case directory
    rocc ciren import ciren -o scn/              # every case below a directory",
    },
    Code {
        code: "E0801",
        title: "malformed CIREN or SAFE file",
        explanation: "The case record is not well-formed XML, or the SAFE extraction is not valid JSON. The
label points at the first place the parser could not accept. Re-export the record from the
CIREN database (or repair the extraction); nothing is written for this case.

    <CaseSummary><Configuration>angle</CaseSummary>   // error: mismatched closing tag",
    },
    Code {
        code: "E0802",
        title: "missing field in a CIREN record or SAFE extraction",
        explanation: "A field the importer needs is absent: for a CIREN record, `CaseSummary/Configuration`,
an `Events/EventSum` row with `AreaOfDamage`, `Contacted` and `ContactedAreaOfDamage`, or the
`GeneralVehicleForm` of a vehicle the event names; for a SAFE extraction, `meta`, `dsl`,
`Actors` (with Model, Initial_position, Actions, Speed) or a `Conflict` field. Fields that only
refine the scene (speeds, lane counts, directions) are not required: their defaults are
warnings (E0807).

    rocc ciren import ciren/100237 -o scn/   # error if the record has no EventSum rows",
    },
    Code {
        code: "E0803",
        title: "unknown code in a CIREN record or SAFE extraction",
        explanation: "A coded value the importer does not map: a damage area other than the CDC areas F, B, L,
R, T, U; a configuration other than angle/sideswipe, head-on, rear end, object; a body type with
no rocc kind; or, in a SAFE extraction, a road_type, Initial_position (W2E, E2W, S2N, N2S,
On-ramp, Main road), Actions, Speed (mph 0..150 or \"N/A\"), Model, vehicle name or impact_type
it does not know. rocc never guesses a value it cannot read: fix the field, or write the
scenario by hand.

    \"Initial_position\": \"NE2SW\"   // error: not W2E, E2W, S2N, N2S, On-ramp or Main road",
    },
    Code {
        code: "E0804",
        title: "crash rocc cannot represent",
        explanation: "The case is read correctly but describes something rocc's staging cannot recreate, and
the message says which: a rollover (rocc stages planar contacts between boxes on the ground), a
non-collision, a pedestrian record, a contact by a vehicle's back, top or undercarriage (rocc
strikes with a front or a side), a fixed object rocc has no kind for (ditch, embankment, curb),
a side impact with a tree, a T-junction approached from its missing leg, a vehicle travelling
across a road the record codes without a junction (out of a driveway: write it by hand on a
`t_junction`), or a SAFE extraction with one vehicle or more than two.

    rocc ciren import ciren/100412 -o scn/   # error: the case codes a rollover",
    },
    Code {
        code: "E0805",
        title: "crash could not be staged on the coded sides",
        explanation: "The importer writes a scenario only after `rocc check` accepts it and the rollout's latched
contact lies on the coded sides: the struck box's side (thirds of each face, as `point` is
defined) and the striker's coded face (front, or the coded side for a sideswipe). Several
impact times are tried; this error means none of them landed there, and it names what the last
attempt did. Nothing is written. Typical cause: an impact the rollout meets square-on (`angle`)
between vehicles whose paths do not let the striker reach the struck side, e.g. a vehicle hit
on its side by oncoming traffic after it spun.

    rocc ciren import ciren/100237 -o scn/   # error: contact landed on the struck vehicle's front, not its right side",
    },
    Code {
        code: "E0806",
        title: "later crash events not staged",
        explanation: "A CIREN record codes several events (a second contact, a sideslap); rocc stages one
conflict per scenario, the first-ranked event. This warning names each event left out.

    rocc ciren import ciren/100237 -o scn/   # warning: event 2 (V1 left side by V2 front) not staged",
    },
    Code {
        code: "E0807",
        title: "importer default or contradiction",
        explanation: "A warning: a field was missing, ambiguous or contradicted by another, and the importer
made a documented choice, also written as a comment in the generated file. Examples: no
narrated direction of travel, no leg count for an intersection, a SAFE `struck_vehicle` that
the `point_of_impact` text contradicts (the point_of_impact, which names the damaged parts, is
followed), a speed of \"N/A\" for a moving vehicle, a `point_of_impact` naming a trailer
rather than a side (staged as a sideswipe).

    // rocc: no narrated direction of travel; V1 staged west to east (E0807)",
    },
    Code {
        code: "E0808",
        title: "point_of_impact cannot be decided",
        explanation: "The SAFE `point_of_impact` text names no vehicle part the importer can map. The rules read
`PART of V<n>` phrases joined by `struck`/`striking` (first strikes), `struck by` (first is
struck) or `and` (head-on), where PART is front, rear/back, left side, right side or a corner
(left-front, ...); a trailer or an unhanded side paired with a handed side is a sideswipe.

    \"point_of_impact\": \"front of V2 striking right side of V1\"",
    },
    Code {
        code: "E0809",
        title: "cannot write imported scenario",
        explanation: "The `.scn` of an imported case could not be written (the directory is not writable, the
disk is full), or two inputs of one batch have the same case id and would write the same
file. Files are written under a temporary name and renamed, so nothing partial is left.

    rocc ciren import ciren -o /read-only/   # error: permission denied",
    },
    Code {
        code: "E0850",
        title: "CIREN case directory or sketch missing",
        explanation: "`rocc ciren extract CASE_DIR` needs a case folder holding the investigator's scene\n\
sketch: `sketch.jpeg` (CIREN case folders), `Sketch.jpg` (SAFE extraction folders), or\n\
`sketch.jpg`, `Sketch.jpeg`, `sketch.png`, `Sketch.png`. The path is not a directory, or none of\n\
these files is there or readable. Nothing is sent to the model.\n
    rocc ciren extract ciren/100237 -o 100237.scn --endpoint ... --model ...",
    },
    Code {
        code: "E0851",
        title: "CIREN case has no crash summary",
        explanation: "The VLM route sends the crash narrative with the sketch. It is read from the\n\
`Summary` element of `crash_report.xml` (CaseSummary/Summary in NHTSA case records), or, when\n\
there is no report, from `Summary.txt`. Neither file exists, the report has no `Summary`\n\
element, or the summary is empty. Coded records without a narrative go through\n\
`rocc ciren import` instead.\n
    rocc ciren extract ciren/100237 -o 100237.scn ...   # error if Summary is empty and there is no Summary.txt",
    },
    Code {
        code: "E0852",
        title: "CIREN crash report is not well-formed XML",
        explanation: "`crash_report.xml` could not be parsed as XML (an unclosed element, a stray `&`, a\n\
truncated download, a DOCTYPE, which rocc refuses). The diagnostic points at the first position\n\
the parser could not accept. Fetch the case record again.\n
    <Summary>V1 & V2 collided</Summary>   <!-- error: a bare `&`; write &amp; -->",
    },
    Code {
        code: "E0853",
        title: "CIREN summary is not UTF-8",
        explanation: "`crash_report.xml` or `Summary.txt` holds bytes that are not UTF-8 (often Latin-1 from an\n\
old export). The message gives the offset and line of the first bad byte. Convert the file:\n
    iconv -f latin1 -t utf-8 Summary.txt > fixed && mv fixed Summary.txt",
    },
    Code {
        code: "E0854",
        title: "CIREN sketch too large or not an image",
        explanation: "The sketch is sent to the vision model as a base64 data URL. Files over 20 MiB are\n\
refused before they are read (servers reject such requests anyway), and a file whose first bytes\n\
are not a JPEG, PNG, GIF or WebP header is refused whatever its name. Scale the sketch down or\n\
replace it with the case's scene diagram.\n
    file sketch.jpeg                                        # check what the sketch really is
    convert sketch.jpeg -resize 2000x2000 sketch.jpeg        # scale a huge scan down",
    },
    Code {
        code: "E0855",
        title: "CIREN case file too large",
        explanation: "The summary is over 16 KiB (CIREN summaries are a few paragraphs, and every byte is sent\n\
again on each repair round), or `crash_report.xml` is over 32 MiB (real ones are about 100 KiB).\n\
The file is refused without being sent.\n
    wc -c Summary.txt crash_report.xml   # the summary must be at most 16 KiB, the report 32 MiB",
    },
    Code {
        code: "E0856",
        title: "extracted scene still fails to check",
        explanation: "The scene the vision model wrote from the sketch and summary did not check (syntax,\n\
names, units, placement or rollout), and `--max-repairs` rounds of sending the diagnostics back\n\
did not fix it. Nothing is written to `-o`; the last attempt is kept beside it as\n\
`NAME.rejected.scn` with its diagnostics. Fix it by hand (`rocc check NAME.rejected.scn`), run\n\
again with a stronger model, or use the coded record (`rocc ciren import`).\n
    rocc check 100237.rejected.scn   # the last attempt, with its diagnostics",
    },
    Code {
        code: "E0857",
        title: "no usable conflict from the model",
        explanation: "The conflict call (temperature 0) must answer one JSON object naming agents of the\n\
extracted scene: `{\"at_fault\": \"v2\", \"struck\": \"v1\", \"impact\": \"angle\", \"point\": \"right\", \"at\": 3}`\n\
(a `.scn` `conflict { ... }` block is accepted too). The reply held no such object, named a party\n\
the scene lacks, used a word outside the impact or point vocabulary, or the scene with the\n\
merged conflict failed to check (for instance, the at-fault vehicle cannot reach the struck one);\n\
`--max-repairs` further conflict calls did not fix it. The scene itself is never re-generated.\n\
Nothing is written to `-o`; the last merged attempt (or the bare scene) is kept as\n\
`NAME.rejected.scn`.\n
    {\"at_fault\": \"v3\", \"struck\": \"v1\", \"impact\": \"angle\", \"point\": \"right\", \"at\": 3}   // error if the scene has no v3",
    },
    Code {
        code: "E0858",
        title: "unusable worked example",
        explanation: "`--examples DIR` replaces the worked examples shown to the model with every `.scn` file of\n\
DIR. Each must pass `rocc check` and carry a `conflict` block (the conflict call's examples are\n\
derived from it). The directory could not be read, holds no `.scn` file, or one file fails.\n
    rocc ciren extract ciren/100237 -o 100237.scn --examples my_examples/ ...   # error if a file has no conflict block",
    },
    Code {
        code: "E0901",
        title: "grounded weights missing",
        explanation: "`--backend grounded` (or `rocc train generator --init`) names a weights file that does not\n\
exist, or `--backend grounded` was given without `--weights`. Train weights first:\n
    rocc compile scenarios/ -o corpus --stage occ --no-previews
    rocc train autoencoder --data corpus --config configs/cpu-small.ron --out model
    rocc train generator   --data corpus --config configs/cpu-small.ron --out model
    rocc compile FILE -o out --backend grounded --weights model/generator.bpk\n\n\
`rocc train` writes `OUT/<stage>.bpk` and the config beside it as `OUT/<stage>.ron`. `rocc edit`\n\
on a clip of the learned backend reruns it with the weights its manifest records; if they moved,\n\
pass the same file with `--weights`.",
    },
    Code {
        code: "E0902",
        title: "grounded config unreadable or invalid",
        explanation: "The model's shapes come from a RON config (`configs/paper.ron`, `configs/cpu-small.ron`).\n\
By default rocc reads the `.ron` next to the weights file (`model/generator.bpk` ->\n\
`model/generator.ron`, which `rocc train` writes); `--grounded-config FILE` names another. The\n\
file could not be read, is not valid RON for `GroundedConfig`, or breaks a rule: `max_foreground`\n\
<= `latents`, decoder `width` a multiple of `heads`, `window` 1..=6 voxels, `min_scale` below\n\
`window / 3`, BEV `strides` of 1 or 2 matching `channels`, `crop` 0 or 16..=400, learning rates\n\
positive with `lr_min <= lr`. The message lists every broken rule.

    ( batch: 0, lr: 1e-3, ... )   // error: `batch` must be at least 1",
    },
    Code {
        code: "E0903",
        title: "weights do not fit the model",
        explanation: "The weights file was read, but its tensors do not match the model the config describes:\n\
a tensor is missing, has another shape, or is not part of the model. Usual causes: the config is\n\
not the one the weights were trained with (use the `.ron` `rocc train` wrote beside them), or the\n\
file is an autoencoder checkpoint where a generator is needed (`--backend grounded` needs\n\
`generator.bpk`). Safetensors files must name tensors by burn's module paths\n\
(`decoder.transformer.layers.0.mha.query.weight`, ...); `rocc train --safetensors` writes a\n\
reference file with every name.

    rocc compile FILE -o out --backend grounded --weights paper/generator.bpk   // error if the
    // weights were trained with configs/cpu-small.ron: pass the matching config beside them",
    },
    Code {
        code: "E0904",
        title: "unknown weights format",
        explanation: "rocc reads weights as burnpack (`.bpk`, what `rocc train` writes and checkpoints) or\n\
safetensors (`.safetensors`, for weights trained elsewhere). Other extensions (`.pt`, `.ckpt`,\n\
`.mpk`) are not read; convert PyTorch state dicts to safetensors with the tensor names of\n\
burn's module paths.

    rocc compile FILE -o out --backend grounded --weights model.safetensors   // error: no tensor
    // named like a burn module path (e.g. `decoder.blocks.0.attn.query.weight`)",
    },
    Code {
        code: "E0905",
        title: "training data unusable",
        explanation: "`rocc train --data DIR` (or `--val DIR`) found no frames, or a frame could not be read.\n\
Two layouts are accepted:
  1. what `rocc compile --stage occ` writes: clips with `boxes.json`, `bev/NNNNNN.npz`,
     `occ/NNNNNN.npy`, at any depth below DIR;
  2. nuPlan-Occ / UniScene style: `DIR/bev/<token>.npz` (gt_bev_masks, gt_aux_bev),
     `DIR/occ/<token>.npy` (dense (400, 400, 32) labels 0..8) or `.npz` (sparse [i, j, k, label]
     rows), `DIR/boxes/<token>.json` ({\"gt_boxes\": [[x, y, z, l, w, h, yaw], ...],
     \"gt_names\": [...]}).\n\
The message names the file and what is wrong with it (shape, dtype, missing key). With\n\
`val_fraction` > 0 and a single clip, nothing is left to train on: add clips or pass `--val`.",
    },
    Code {
        code: "E0906",
        title: "cannot write training output",
        explanation: "`rocc train` could not create or write its output directory, a checkpoint, the weights or\n\
the history file (permissions, full disk), or could not read back a checkpoint for `--resume`.\n\
Files are written atomically, so an interrupted run leaves the previous checkpoint intact.

    rocc train autoencoder --data corpus --config configs/cpu-small.ron --out /read-only/dir",
    },
    Code {
        code: "E0907",
        title: "training diverged",
        explanation: "The loss became NaN or infinite. Lower the stage's learning rate (`train.autoencoder.lr`,\n\
`train.generator.lr`) in the config, and continue from the last good checkpoint with\n\
`--resume` (checkpoints are written every `checkpoint_every` steps and at each epoch's end).

    rocc train generator --data corpus --config configs/cpu-small.ron --out model --resume   // error: nothing to resume",
    },
    Code {
        code: "E0908",
        title: "bad backend or device option",
        explanation: "An option of the learned backend does not apply: `--weights` or `--grounded-config` given\n\
with `--backend procedural`, or `--device wgpu|cuda` on a build without the `gpu` feature\n\
(`cargo build --release --features gpu`; CI and the default build are CPU-only).

    rocc train autoencoder --data corpus --config configs/paper.ron --out paper --device cuda   // error in a default build",
    },
    // ---- E10xx: expectations and `rocc test` ----
    Code {
        code: "E1001",
        title: "expectation time outside the clip",
        explanation: "An `expect` line's window (`during A..B s` or `by T s`) must lie within the clip, from 0 to the\n\
scenario's `duration`; `by` takes one time, not a range.\n
    duration 6 s
    expect { contact striker with ego by 8 s }     // error: the clip ends at 6 s\n\n\
Shorten the window or lengthen the clip. See docs/library-testing.md.",
    },
    Code {
        code: "E1002",
        title: "landmark not on the agent's lane",
        explanation: "`stopped A before LANDMARK` and `reach A LANDMARK` measure along the lane agent A starts in, so\n\
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
        explanation: "`no_contact` (any two boxes) or `no_contact A with B` holds when the boxes never overlap within\n\
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
        explanation: "`reach A LANDMARK by T s` holds when the front of A's box reaches the landmark, measured along the\n\
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
        explanation: "A path given to `rocc test` does not exist, or a folder holds no `.scn` file (subfolders are not\n\
searched: they hold kind files and snapshots).\n
    rocc test empty/     // error: the folder holds no .scn file",
    },
    Code {
        code: "E1024",
        title: "cannot write a test output",
        explanation: "A snapshot, pending `.snap.new` or `--junit` report could not be written (folder missing or not\n\
writable), or `--review` could not read an answer. Files are written to a temporary name and\n\
renamed, so no half file is left.\n
    rocc test scenarios/ --junit missing/dir/report.xml     // error: cannot write",
    },
];

pub fn lookup(code: &str) -> Option<&'static Code> {
    let code = code.trim().to_ascii_uppercase();
    CODES.iter().find(|c| c.code == code)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reader of `rocc explain` has the repository at most: a file it cites is a page under
    /// `docs/`, never a reference file kept beside the repository or a section of another page.
    #[test]
    fn explanations_cite_only_files_users_have() {
        for c in CODES {
            let text = c.explanation;
            assert!(!text.contains("shared/"), "{}: cites a reference folder users do not have", c.code);
            assert!(!text.contains("README"), "{}: cites the README instead of a docs page", c.code);
            for (i, _) in text.match_indices(".md") {
                let path_char = |ch: char| ch.is_ascii_alphanumeric() || "/_-".contains(ch);
                let start =
                    text[..i].char_indices().rev().take_while(|(_, ch)| path_char(*ch)).last().map_or(i, |(j, _)| j);
                let file = &text[start..i + 3];
                assert!(file.starts_with("docs/"), "{}: cites `{file}`, which users do not have", c.code);
            }
        }
    }
}
