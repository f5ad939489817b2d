//! E0870-E0879: near misses across a path.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0870",
        title: "near miss by `ttc` across a path cannot be staged",
        explanation: "A `ttc` near miss whose passer does not start behind the passed agent in its line closes\n\
across the passed agent's path: the passer keeps to its own route and reaches, at the stated\n\
time, the place and speed from which braking as hard as it can brings the two boxes to `ttc`\n\
(their constant-velocity time to collision) and no closer; it stops short and drives on once\n\
the way is clear. The rolled-out boxes are measured: no contact, a time to collision over the\n\
clip at most 0.15 s below `ttc`, and within 0.5 s of `at` one within `ttc` + 0.15 s. Otherwise\n\
the scene is refused, saying what happened: routes that do not cross near that time, a passer\n\
too fast to stop short within `ttc` (about 2 x its emergency braking x `ttc`), or one that\n\
cannot reach the place in time within its limits. Start the two where their routes cross near\n\
`at`, slow the passer, or move `at` (docs/language.md, near misses).\n
    // v1 north at 8 m/s and v2 east at 10 m/s, each 30 m before the junction's stop line
    near_miss { passer v1; passed v2; ttc 0.8 s; at 3 s }     // fine
    near_miss { passer v1; passed v2; ttc 0.8 s; at 0.5 s }   // error: too soon to get there",
    },
    Code {
        code: "E0871",
        title: "a walker as the passer of a `ttc` near miss across a path",
        explanation: "Across a path, the passer of a `ttc` near miss is the vehicle that closes on the other and\n\
brakes short; a walker or an animal does not. To stage a car closing on a pedestrian crossing in\n\
front of it, make the car the passer.\n
    // walker crossing the road in front of car
    near_miss { passer car; passed walker; ttc 1 s; at 3 s }   // fine
    near_miss { passer walker; passed car; ttc 1 s; at 3 s }   // error",
    },
];
