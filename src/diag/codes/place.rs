//! E02xx: road and placement.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0201",
        title: "placement off a valid surface",
        explanation: "Each class starts where it can physically be: moving vehicles on lanes, shoulders,\n\
the junction, a parking lane or a driveway; moving bicycles also on sidewalks and crosswalks;\n\
people, animals and static things of any class (cones, debris, a wreck) anywhere on the map or\n\
within 10 m of it, lanes included.\n
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
    // ---- greens per approach (E0233-E0236) ----
    Code {
        code: "E0233",
        title: "a per-approach green that cannot run",
        explanation: "`signal_north A..B s` (and `signal_east`, `signal_south`, `signal_west`) gives that\n\
approach its green from A to B seconds into the cycle, then `signal_yellow`, then red. A green is\n\
a range that starts before it ends, within 0..600 s, on an approach the template has (a\n\
`t_junction` has no north), and the cycle (`signal_cycle`) must hold every green and its yellow.\n
    road four_way { signals on; signal_cycle 40 s; signal_north 0..15 s; signal_south 0..15 s; signal_east 20..35 s; signal_west 20..35 s }   // fine
    road four_way { signals on; signal_north 15 s; ... }                                                                                    // error: one time",
    },
    Code {
        code: "E0234",
        title: "an approach without a green",
        explanation: "Once one approach states its own green, every approach of the junction does: one left\n\
out would stay red for good.\n
    road t_junction { signals on; signal_west 0..15 s; signal_east 0..15 s; signal_south 20..30 s }   // fine
    road t_junction { signals on; signal_west 0..15 s; signal_east 0..15 s }                          // error: south",
    },
    Code {
        code: "E0235",
        title: "two-phase timing mixed with greens per approach",
        explanation: "`signal_green` and `signal_all_red` time the two-phase cycle; greens stated per approach\n\
replace it, so the two are not given together. `signal_cycle` is the length of a cycle of\n\
per-approach greens and means nothing without them.\n
    road four_way { signals on; signal_green 20 s }                            // fine
    road four_way { signals on; signal_green 20 s; signal_north 0..15 s; ... } // error",
    },
    Code {
        code: "E0236",
        title: "crossing approaches green at once",
        explanation: "Approaches whose traffic crosses (north or south against east or west) may not show green\n\
or yellow at the same time: the greens would send both into the junction together. Opposite\n\
approaches may overlap as they like, which is how a leading or lagging phase (a protected\n\
left) is written.\n
    road four_way { signals on; signal_south 0..12 s; signal_north 4..12 s; signal_east 16..26 s; signal_west 16..26 s }   // fine: south leads
    road four_way { signals on; signal_south 0..12 s; signal_north 0..12 s; signal_east 10..26 s; signal_west 16..26 s }   // error",
    },
    // ---- flaggers (E0270-E0272) ----
    Code {
        code: "E0270",
        title: "a flagger that is not a standing person",
        explanation: "`flag { ... }` makes an agent a flagger: a person (a kind of class pedestrian) who\n\
stands where it is placed and directs traffic. A vehicle, an object or an animal cannot; nor can\n\
a person with a goal, a speed or a replayed track.\n
    agent f: adult { at west.in[1], 20 m before center offset 3 m right heading 180 deg; flag { stop } }   // fine
    agent f: sedan { at west.in[1], 20 m before center; flag { stop } }                                   // error",
    },
    Code {
        code: "E0271",
        title: "a flag program that cannot run",
        explanation: "A `flag` block lists the states a flagger shows, `stop` or `go`, in order. Either the\n\
first is shown from the start and each later one begins `after` a clip time (in order, within\n\
the clip) or `when` a trigger condition holds; or every state has a length and they repeat as a\n\
cycle. An empty block, more than 32 states, another word, a first state with a time, or a mix\n\
of the two forms is refused.\n
    flag { stop; go after 8 s; stop when car within 20 m }   // fine
    flag { stop 20 s; go 15 s }                              // fine: a cycle
    flag { stop; go 15 s }                                   // error: `after` or `when` after the first",
    },
    Code {
        code: "E0272",
        title: "a flagger facing no approach",
        explanation: "A flagger directs the traffic that comes toward its face: the lanes it stands on or\n\
beside (within a metre of their paving, shoulder included) whose traffic heads within 60\n\
degrees of straight at it. `heading` is its world yaw: on a `straight` road, one facing\n\
eastbound traffic on `west.in` has `heading 180 deg`. A flagger off the road, or facing the way\n\
the traffic goes, directs nobody.\n
    agent f: adult { at west.in[1], 20 m before center offset 3 m right heading 180 deg; flag { stop } }   // fine
    agent f: adult { at west.in[1], 20 m before center offset 3 m right heading 0 deg; flag { stop } }     // error",
    },
    // ---- lamps and doors (E0240) ----
    Code {
        code: "E0240",
        title: "headlights or hazards on a kind without them",
        explanation: "`lights on|off` (headlights) is for vehicles and bicycles; `hazards on|off` for vehicles.\n\
A person, an animal or an object has no lamps, and a bicycle no hazard lights.\n
    agent car: sedan { at west.in[1], 20 m before center; lights on; hazards on }  // fine
    agent bike: bicycle { at west.in[1], 30 m before center; lights on }          // fine
    agent kid: child { at sidewalk(west.in), 10 m before center; lights on }      // error",
    },
    Code {
        code: "E0241",
        title: "beacons on a kind without them",
        explanation: "`beacons on|off` sets the flashing roof lights of an emergency vehicle (`ambulance`,\n\
`fire_truck`, `police_car` and kinds derived from them), which are on with the siren unless\n\
stated. `beacons on` with `siren off` drives with lights only: traffic does not make way.\n
    agent amb: ambulance { at west.in[1], 60 m before center; siren off; beacons on }  // fine
    agent car: sedan { at west.in[1], 20 m before center; beacons on }                 // error",
    },
    Code {
        code: "E0242",
        title: "a door on a kind without doors",
        explanation: "`door NAME open|close ...` swings a side door of a car, van, truck or bus (class\n\
`vehicle`, not `motorcycle`). A walker, a cyclist, a motorcycle or an object has no doors.\n
    object parked: sedan { at east.in[1], 10 m after center offset 2.8 m right; door front_left open at 2 s }  // fine
    agent bike: bicycle { at east.in[1], 30 m before center; door front_left open at 2 s }                    // error",
    },
    Code {
        code: "E0243",
        title: "a door trigger that cannot be read",
        explanation: "A door opens or closes at a time (`at 3 s`) or when another agent comes `within` a\n\
distance or its time to collision falls `under` a time. `reaches`, `headway` and `starts` watch\n\
a road user's own route or goal, which a door does not follow.\n
    door front_left open when bike within 8 m          // fine
    door front_left open when bike ttc under 2 s       // fine
    door front_left open when bike starts              // error",
    },
];
