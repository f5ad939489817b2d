//! E01xx: the checker.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0101",
        title: "unit of the wrong dimension",
        explanation: "Numbers carry units and each statement expects one dimension:
  length m, cm, km; speed m/s, km/h, mph; time s, ms; angle deg, rad; frequency Hz; ratio %;
  mass kg.\n\
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
        title: "agent strikes twice at once",
        explanation: "An agent may strike several times, one contact after the other (it glances off one car\n\
into another), but not two at the same time: its strikes need different `at` times (a\n\
conflict without `at` is at half the clip). Both blocks are shown.\n
    conflict { at_fault a; struck b; impact sideswipe; point left; at 2 s }
    conflict { at_fault a; struck c; impact angle; point left; at 2 s }     // error: both at 2 s
    conflict { at_fault a; struck c; impact angle; point left; at 3 s }     // fine: the slide reaches c",
    },
    Code {
        code: "E0122",
        title: "a strike after a latch",
        explanation: "`after latch` holds a crashed pair where it met for the rest of the clip, so neither of\n\
the two strikes again later. Without the latch both move on from the impact (they slide to\n\
rest) and either may strike again, or the struck one strike another: the contact its slide\n\
brings about.\n
    conflict { at_fault tail; struck mid; impact rear_end; point rear; at 2 s; after latch }
    conflict { at_fault mid; struck lead; impact rear_end; point rear; at 3 s }   // error: `mid` is held
    conflict { at_fault tail; struck mid; impact rear_end; point rear; at 2 s }
    conflict { at_fault mid; struck lead; impact rear_end; point rear; at 3 s }   // fine: pushed into `lead`",
    },
    Code {
        code: "E0123",
        title: "a pair that crashes twice",
        explanation: "A pair is staged to crash once (after it, neither is driven): a second conflict\n\
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
        code: "E0135",
        title: "recorded box dropped",
        explanation: "A warning of `rocc import boxes`: a recorded box that no body could have followed from the\n\
boxes before it (a detector's glitch: a box jumping metres in one frame) breaks a limit of the\n\
track checks (E0131-E0134). It is dropped and the track is interpolated across it; where the\n\
box jumps and stays, the rest of the track becomes an agent of its own (`NAME_from_FRAME`).\n\
The warning names the track, the clip frame and the limit.\n
    rocc import boxes glitchy.json --convention nuplan -o scene.scn   // warning E0135 per dropped box",
    },
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
and only after that goal has started. A phase gives a `start` and what changes then, each at\n\
most once: a `speed`, `stop after DIST` (counted from where the phase starts) and, for a vehicle\n\
whose first goal holds its lane, `lateral pull_to_shoulder` or (E0156) `lateral change_lane\n\
SIDE`; without a `speed` it keeps the one before. Turns, crossings and the other stops\n\
belong to the first goal block.\n\
Static things and replayed tracks have no phases.\n
    goal { speed 10 m/s }
    goal { speed 0 m/s; start when car headway under 1.5 s }     // fine: brakes to a stop
    goal { lateral pull_to_shoulder; stop after 40 m; start after 3 s }  // fine: pulls over
    goal { speed 4 m/s; turn left; start after 1 s }             // error: a turn in a phase",
    },
    Code {
        code: "E0156",
        title: "lane change in a goal phase that cannot be driven",
        explanation: "A vehicle's phase may change to the next lane of its road (`lateral change_lane left` or\n\
`right`): it keeps its lane until the phase starts, then moves over. Its route is the target\n\
lane from the start, so the first goal holds its lane and neither turns nor reverses, and the\n\
agent makes no other lateral move in a phase (one lane change, no pull-over besides).\n
    goal { speed 10 m/s }
    goal { lateral change_lane left; start when ego within 20 m }   // fine
    goal { speed 10 m/s; turn left }
    goal { lateral change_lane left; start after 2 s }              // error: its goal turns",
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
    // ---- near misses by time to collision (E0187-E0189) ----
    Code {
        code: "E0187",
        title: "near miss by `ttc` with `gap` or `side`",
        explanation: "A near miss is either a pass alongside (`gap`, optionally `side`) or a close approach by time\n\
to collision (`ttc`): from behind in its line or across its path, on no side. Keep one form.\n
    near_miss { passer a; passed b; ttc 0.8 s; at 3 s }              // fine
    near_miss { passer a; passed b; gap 0.5 m; ttc 0.8 s }           // error: both forms
    near_miss { passer a; passed b; ttc 0.8 s; side left }           // error: no side from behind",
    },
    Code {
        code: "E0188",
        title: "near-miss time to collision out of range",
        explanation: "`ttc` is the least constant-velocity time to collision between the two boxes, 0.5..3 s:\n\
zero or less is contact (stage a `conflict`); below 0.5 s no braking within a vehicle's limits\n\
stops short; beyond 3 s the passer is following, not closing.\n
    near_miss { passer a; passed b; ttc 0.8 s }              // fine
    near_miss { passer a; passed b; ttc 0 s }                // error: contact
    near_miss { passer a; passed b; ttc 10 s }               // error: not near",
    },
    Code {
        code: "E0189",
        title: "near miss by `ttc` cannot be staged",
        explanation: "The passer comes up behind the passed agent in its line, faster than it, to a gap of the\n\
closing speed times `ttc` at the stated time, then drives its route again and brakes behind it.\n\
The rolled-out boxes are measured: no contact, a time to collision over the clip at most 0.15 s\n\
below `ttc`, and within 0.5 s of `at` one within `ttc` + 0.15 s. Otherwise the scene is refused,\n\
saying what happened. Start the passer behind the passed agent in its lane and faster, or move\n\
`at`.\n
    // v1 at 15 m/s, 25 m behind v2 at 10 m/s in its lane
    near_miss { passer v1; passed v2; ttc 0.8 s; at 3 s }     // fine
    near_miss { passer v1; passed v2; ttc 0.8 s; at 0.5 s }   // error: no way to close so soon",
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
];
