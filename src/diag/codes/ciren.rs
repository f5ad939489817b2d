//! E08xx: CIREN crash recreation (`rocc ciren`): E0800-E0849 records and SAFE extractions;
//! E0850-E0899 the VLM route (`rocc ciren extract`): case files, the conflict descriptor.

use super::Code;

pub const CODES: &[Code] = &[
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
`t_junction`), or a SAFE extraction with one vehicle, or more than two and one impact. For
records with several events and SAFE `Conflict` lists: a vehicle that strikes a vehicle
already in the crash in two events, or after it was struck, or strikes a moving vehicle on its
slide (the slide after an impact is not staged; a fixed object or a stopped vehicle is placed
where it goes, others are not), a pair that meets in two events, a later event involving neither
vehicle of the first-ranked one, or a fixed object struck before any other contact of its
striker.

    rocc ciren import ciren/100412 -o scn/   # error: the case codes a rollover",
    },
    Code {
        code: "E0805",
        title: "crash could not be staged on the coded sides",
        explanation: "The importer writes a scenario only after `rocc check` accepts it and the rollout's latched
contact of every event lies on its coded sides: the struck box's side (thirds of each face, as
`point` is defined) and the striker's coded face (front, or the coded side for a sideswipe), and
meets the coded clock direction of the principal force within an hour. Several impact times, and
speeds solved for the coded force, are tried; this error means none of them landed there, and it
names what the last attempt did. Nothing is written. Typical cause: an impact the rollout meets square-on (`angle`)
between vehicles whose paths do not let the striker reach the struck side, e.g. a vehicle hit
on its side by oncoming traffic after it spun. A fixed object or stopped vehicle struck on
the slide after an impact is placed where the slide takes the striker's coded face; E0805 then says why no place
worked (that face never leads the slide at 1 m/s or more clear of the others, as when a T-bone
striker stops against the car it struck).

    rocc ciren import ciren/100237 -o scn/   # error: contact landed on the struck vehicle's front, not its right side",
    },
    Code {
        code: "E0806",
        title: "closing speed off the coded delta-V",
        explanation: "A warning: the contact lands on its coded sides and meets the coded clock direction of the
principal force, but the closing speed at contact is more than 20% from the one the coded
delta-V implies (momentum with a common velocity after, masses from curb weights or class
priors). The importer solves the speeds at contact and stages again; the rollout's staging sets
the striker's speed in its last seconds, so the closing speed is the staging's. The file is
written; the warning gives both speeds.

    rocc ciren import tests/fixtures/ciren-chains/rear-end-chain.xml -o scn/",
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
];
