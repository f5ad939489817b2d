//! E0250-E0259: reversing, parking lanes and driveways.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0250",
        title: "a reverse goal for something that does not reverse",
        explanation: "`reverse` drives a vehicle backwards, rear first. Walkers and animals turn round and walk\n\
(give them a `heading`); bicycles are ridden forward; objects do not move at all.\n
    agent car: sedan { at driveway(d1); goal { reverse into east.out[1] } }   // fine
    agent kid: child { at sidewalk(east.out), 5 m after center; goal { reverse 2 m } }   // error",
    },
    Code {
        code: "E0251",
        title: "reversing too fast, or from a moving start",
        explanation: "A vehicle reverses at walking pace: its goal `speed` is at most 3 m/s (1.5 m/s without\n\
one), and it starts from rest, so the agent itself takes no `speed`. A negative speed is not a\n\
reverse (E0103): use the goal.\n
    agent car: sedan { at driveway(d1); goal { reverse into east.out[1]; speed 2 m/s } }   // fine
    agent car: sedan { at driveway(d1); goal { reverse into east.out[1]; speed 20 km/h } } // error",
    },
    Code {
        code: "E0252",
        title: "a reverse goal with a forward goal beside it",
        explanation: "A reverse goal says where the vehicle ends: straight back a distance, or rear first into a\n\
lane. A `turn`, a `stop` or a lateral move in the same goal would drive it forward; the vehicle\n\
stops when its reverse is done.\n
    goal { reverse 8 m; start after 2 s }          // fine
    goal { reverse 8 m; turn left }                // error",
    },
    Code {
        code: "E0253",
        title: "a lane that cannot be reversed into",
        explanation: "`reverse into ARM.DIR[K]` backs a vehicle out of a driveway or a parking slot into a lane\n\
of the road: the lane must exist, and the vehicle must start off the lanes (`at driveway(NAME)` or\n\
`at parking(ARM.DIR)[K]`) beside it, far enough from the lane's start to swing in. On a lane,\n\
`reverse DIST` backs straight along it.\n
    agent car: sedan { at driveway(d1); goal { reverse into east.out[1] } }   // fine
    agent car: sedan { at east.out[1], 20 m after center; goal { reverse into east.out[1] } }   // error",
    },
    Code {
        code: "E0254",
        title: "parking lanes or driveways on a road other than straight",
        explanation: "Parking lanes and driveways are laid along the kerbs of a `straight` road.\n\
See docs/language.md (Roads, parking lanes and driveways).\n
    road straight { sidewalks on; parking east out; driveway d1 west.in 20 m }   // fine
    road four_way { parking north both }                                          // error",
    },
    Code {
        code: "E0255",
        title: "overlapping parking lanes, driveways or slots",
        explanation: "One parking lane per kerb (`both` covers the in and out kerbs of an arm); driveways on one\n\
kerb keep their width (3.5 m) apart; a parking slot across a driveway's mouth is kept clear.\n
    road straight { sidewalks on; parking east both; parking east out }   // error: east.out twice
    object p: sedan { at parking(east.out)[5] }   // error if driveway d1 east.out 30 m crosses slot 5",
    },
    Code {
        code: "E0256",
        title: "a driveway on a road without sidewalks",
        explanation: "A driveway crosses the sidewalk from the kerb to the property beyond: a road without\n\
sidewalks has none to cross. Add `sidewalks on`.\n
    road straight { sidewalks on; driveway d1 east.out 20 m }   // fine
    road straight { driveway d1 east.out 20 m }                 // error",
    },
    Code {
        code: "E0257",
        title: "a driveway off its arm",
        explanation: "A driveway's position is its centre's distance along the arm from the road's centre: the\n\
whole 3.5 m width must lie on the arm (half the road's `length`), clear of a mid-block crosswalk\n\
(3 m from the centre).\n
    road straight { length 120 m; sidewalks on; driveway d1 east.out 20 m }   // fine
    road straight { length 120 m; sidewalks on; driveway d1 east.out 80 m }   // error",
    },
    Code {
        code: "E0258",
        title: "a parking slot that does not exist",
        explanation: "Parking slots are 6 m long, numbered 1, 2, ... from the road's centre outward along the\n\
arm: a 120 m straight road has 10 per kerb (fewer with a crosswalk). A longer road has more.\n
    object p: sedan { at parking(east.out)[3] }    // fine
    object p: sedan { at parking(east.out)[40] }   // error",
    },
    Code {
        code: "E0259",
        title: "no such parking lane or driveway",
        explanation: "`parking(ARM.DIR)[K]` needs a parking lane along that kerb (`parking ARM in|out|both` in\n\
the road block); `driveway(NAME)` needs a driveway of that name.\n
    road straight { sidewalks on; parking east out; driveway d1 east.out 30 m }
    object p: sedan { at parking(west.in)[2] }   // error: no parking along west.in
    agent c: sedan { at driveway(d2) }           // error: no driveway d2",
    },
];
