//! E0124-E0129: what an impact needs from the file (masses, a conflict's `after`, `restitution`
//! and `friction`). E0196-E0199: the order of an agent's several crashes, and a strike that
//! follows an impact.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0124",
        title: "mass out of range",
        explanation: "`mass` on an agent or a kind is what the body weighs in an impact: one value in kg within\n\
10..60000 kg. Unstated, it comes from the class and the box (vehicles 120 kg per cubic metre\n\
of box, walkers 110, a bicycle with its rider 90 kg); see docs/rollout.md.\n
    agent car: sedan { at west.in[1], 20 m before center; mass 1500 kg }   // fine
    agent bus: bus { at west.in[1], 60 m before center; mass 90000 kg }    // error: out of range
    agent van: van { at west.in[1], 40 m before center; mass 2000..2500 kg } // error: a range",
    },
    Code {
        code: "E0125",
        title: "mass on something that never moves",
        explanation: "An object, or an agent of a static kind (a pole, a tree, a barrier), stands when struck: the\n\
impact model takes it as immovable, so it has no mass to state.\n
    object pole: pole { at west.in[1], 15 m after center offset 3 m right; mass 200 kg }  // error",
    },
    Code {
        code: "E0126",
        title: "unknown `after` of a conflict",
        explanation: "What follows a conflict's contact: `after slide` (the default) resolves the impact and lets\n\
both bodies slide and spin to rest; `after latch` holds the pair where it met for the rest of\n\
the clip.\n
    conflict { at_fault a; struck b; impact rear_end; point rear; at 2 s; after latch }   // fine
    conflict { at_fault a; struck b; impact rear_end; point rear; at 2 s; after stop }    // error",
    },
    Code {
        code: "E0127",
        title: "restitution out of range",
        explanation: "`restitution` is the coefficient of restitution of a conflict's impact, a plain number from\n\
0 (the bodies move on together) to 1 (no energy lost); 0.1 when unstated.\n
    conflict { at_fault a; struck b; impact angle; point left; restitution 0.3 }   // fine
    conflict { at_fault a; struck b; impact angle; point left; restitution 1.4 }   // error",
    },
    Code {
        code: "E0128",
        title: "friction out of range",
        explanation: "`friction` is the friction between the two bodies of a conflict's impact, the largest ratio\n\
of tangential to normal impulse: a plain number within 0..1.5; 0.5 when unstated.\n
    conflict { at_fault a; struck b; impact sideswipe; point left; friction 0.3 }   // fine
    conflict { at_fault a; struck b; impact sideswipe; point left; friction 30 % }  // error: a plain number",
    },
    Code {
        code: "E0129",
        title: "an impact coefficient on a latched pair",
        explanation: "`after latch` holds the pair where it met, so no impact is resolved and `restitution` or\n\
`friction` would have no effect: the two settings contradict each other.\n
    conflict { at_fault a; struck b; impact rear_end; point rear; after latch; restitution 0.2 }  // error",
    },
    Code {
        code: "E0196",
        title: "strikes written out of time order",
        explanation: "An agent may strike several times (it glances off one car and into another, or into a\n\
pole), one contact after the other: its conflicts are written in the order they happen, each\n\
at a later `at` than the one before. Both blocks are shown.\n
    conflict { at_fault a; struck b; impact sideswipe; point left; at 4 s }
    conflict { at_fault a; struck pole; impact object; point front; at 3 s }   // error: 3 s comes first\n\n\
Swap the two blocks, or their times.",
    },
    Code {
        code: "E0197",
        title: "a latch on a strike that follows an impact",
        explanation: "An agent that has struck or been struck is not driven from that contact on: it slides and\n\
spins to rest, and its next contact is resolved as an impact. `after latch` (hold the pair\n\
where it met) is a staged crash's, not such a contact's.\n
    conflict { at_fault a; struck b; impact sideswipe; point left; at 2 s }
    conflict { at_fault a; struck pole; impact object; point front; at 3 s; after latch }   // error",
    },
    Code {
        code: "E0199",
        title: "a strike that follows an impact does not happen as asked",
        explanation: "A conflict whose at-fault agent has struck or been struck earlier is not staged with an\n\
intercept: the motion after the earlier impact must bring the two together, and the rolled-out\n\
boxes are measured. The contact must come within 1.5 s of `at` and land on the struck agent's\n\
`point` (an object's too: it is not turned to face the striker); the striker touches with whatever side the slide leads with.\n\
Otherwise the scene is refused, saying what happened. Start the struck agent where the slide\n\
reaches it, change the earlier crash (its speeds, side or time), or move `at`.\n
    conflict { at_fault suv; struck sedan; impact angle; point left; at 2.5 s }
    conflict { at_fault sedan; struck pole; impact object; point left; at 3.5 s }   // the sedan's slide must reach the pole",
    },
];
