//! The emitter. In: a `Crash`. Out: `.scn` text whose staged collision lands on the coded
//! sides, verified by running the checker and the front (sample, road, place, rollout) on it.
//!
//! Placements are chosen so both vehicles reach the conflict area at the impact time on their
//! own goals; the rollout then re-plans the striker's last seconds onto the coded side. A few
//! timings are tried in a fixed order and the first whose staged contact is on the coded sides
//! is kept, so the result is deterministic and never unverified.

use super::crash::{Crash, Face, Manoeuvre, Side, Template, VehicleDesc, impact_name};
use crate::check::scenario::{Impact, Point};
use crate::diag::Diagnostic;
use crate::source::SourceMap;
use std::fmt::Write as _;
use std::path::Path;

/// Impact time and how much later (s) the striker would reach the conflict area on its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Staging {
    pub t_impact: f64,
    pub lag: f64,
}

/// The striker's lags tried (s), in order; each with every impact time of `TIMES`.
const LAGS: [f64; 6] = [0.0, 0.5, 1.0, -0.5, 1.5, 2.0];
const TIMES: [f64; 5] = [4.0, 3.5, 4.5, 3.0, 5.0];

/// What the verified staging did.
#[derive(Clone, Debug, PartialEq)]
pub struct Staged {
    pub text: String,
    pub staging: Staging,
    /// Latched impact frame and time (s).
    pub frame: usize,
    pub time: f64,
    pub struck_side: Point,
    /// What the staging met only in part (a closing speed off its delta-V), for warnings.
    pub shortfalls: Vec<String>,
}

/// A number as the language writes it: integers bare, otherwise one decimal.
pub fn num(x: f64) -> String {
    let r = (x * 10.0).round() / 10.0;
    if (r - r.round()).abs() < 1e-9 { format!("{}", r.round() as i64) } else { format!("{r:.1}") }
}

/// A coordinate to the centimetre, as the language writes it.
fn num2(x: f64) -> String {
    let r = (x * 100.0).round() / 100.0;
    let s = format!("{r:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn comment_lines(out: &mut String, indent: &str, lines: &[String]) {
    for l in lines {
        for part in l.lines() {
            let _ = writeln!(out, "{indent}// {part}");
        }
    }
}

/// Distance from a junction's stop line to the middle of the junction, m (see road/junction.rs:
/// the junction box spans the crossing road's lanes and median, the stop line is 1 m out).
fn stop_to_centre(c: &Crash) -> f64 {
    f64::from(c.road.lanes) * c.road.lane_width + c.road.median / 2.0 + c.road.shoulder + 1.0
}

/// Where the merge area's middle lies past the `junction` landmark, m (road/merge.rs: x = -40..40).
const MERGE_MID: f64 = 40.0;

/// The distance before the landmark that brings `v` to the conflict area at `t`.
fn lead_distance(c: &Crash, v: &VehicleDesc, t: f64) -> f64 {
    let speed = v.speed_kmh / 3.6;
    let to_conflict = match c.road.template {
        Template::FourWay | Template::TJunction => stop_to_centre(c),
        Template::Merge => MERGE_MID,
        Template::Straight | Template::Curve { .. } => 0.0,
    };
    (speed * t - to_conflict).max(3.0)
}

/// Seconds between successive contacts of a multi-event crash, in time order.
pub const EVENT_GAP: f64 = 2.0;

/// The time of each conflict (time order): the staged ones in slots `EVENT_GAP` apart, a strike on
/// a slide at its measured time.
pub(super) fn conflict_times(c: &Crash, st: Staging) -> Vec<f64> {
    let mut slot = 0;
    c.conflicts
        .iter()
        .map(|k| {
            k.at.unwrap_or_else(|| {
                slot += 1;
                st.t_impact + EVENT_GAP * (slot - 1) as f64
            })
        })
        .collect()
}

/// When `name` first reaches a contact: its own strike (the striker's lag added) or the first
/// contact that strikes it; the first contact's time for a vehicle in none.
fn first_contact(c: &Crash, st: Staging, name: &str) -> f64 {
    let at = conflict_times(c, st);
    let times = c.conflicts.iter().enumerate().filter_map(|(i, k)| {
        let t = at[i];
        if k.at_fault == name {
            Some(t + st.lag)
        } else if k.struck == name {
            Some(t)
        } else {
            None
        }
    });
    times.reduce(f64::min).unwrap_or(st.t_impact)
}

/// Per-vehicle distance before the landmark.
fn distances(c: &Crash, st: Staging) -> Vec<f64> {
    c.vehicles
        .iter()
        .map(|v| {
            if v.manoeuvre == Manoeuvre::Stopped {
                return 3.0;
            }
            let d = lead_distance(c, v, first_contact(c, st, &v.name));
            // A rear-end striker is in the same lane, behind the struck vehicle: at least a car
            // length and a gap back.
            let behind = c.conflicts.iter().filter(|k| k.at_fault == v.name && k.impact == Impact::RearEnd);
            behind.filter_map(|k| c.vehicle(&k.struck)).fold(d, |d, s| {
                let ds = if s.manoeuvre == Manoeuvre::Stopped {
                    3.0
                } else {
                    lead_distance(c, s, first_contact(c, st, &s.name))
                };
                d.max(ds + 12.0 + 5.0 * st.lag)
            })
        })
        .collect()
}

fn landmark(t: Template) -> &'static str {
    match t {
        Template::FourWay | Template::TJunction => "stop_line",
        Template::Merge => "junction",
        Template::Straight | Template::Curve { .. } => "center",
    }
}

fn goal(c: &Crash, v: &VehicleDesc) -> String {
    let s = num(v.speed_kmh);
    let junction = c.road.template.has_junction();
    match v.manoeuvre {
        Manoeuvre::Stopped => "goal { speed 0 km/h }".into(),
        Manoeuvre::TurnLeft => format!("goal {{ speed {s} km/h; turn left }}"),
        Manoeuvre::TurnRight => format!("goal {{ speed {s} km/h; turn right }}"),
        Manoeuvre::ChangeLaneLeft => format!("goal {{ speed {s} km/h; lateral change_lane left }}"),
        Manoeuvre::ChangeLaneRight => format!("goal {{ speed {s} km/h; lateral change_lane right }}"),
        Manoeuvre::Straight if junction => format!("goal {{ speed {s} km/h; turn straight }}"),
        Manoeuvre::Straight | Manoeuvre::Merge => format!("goal {{ speed {s} km/h }}"),
    }
}

/// The seed: the numeric case id, or a stable hash of it.
fn seed(id: &str) -> u64 {
    id.parse().unwrap_or_else(|_| crate::fsio::fnv1a(id.as_bytes()))
}

/// The `.scn` text of a crash under one staging.
pub fn emit(c: &Crash, st: Staging) -> String {
    let ds = distances(c, st);
    let far = ds.iter().copied().fold(0.0, f64::max);
    let mut out = String::new();
    comment_lines(&mut out, "", &c.header);
    let at = conflict_times(c, st);
    // The staged contacts set the clip's length; a strike on a slide lies inside it (`slide`).
    let staged = c.conflicts.iter().zip(&at).filter(|(k, _)| k.at.is_none()).map(|(_, t)| *t);
    let duration = (staged.fold(st.t_impact, f64::max) + 4.0).ceil().max(8.0);
    let _ = writeln!(out, "scenario {} {{", c.scenario_name());
    let _ = writeln!(out, "    seed {}", seed(&c.id));
    let _ = writeln!(out, "    duration {} s", num(duration));
    let _ = writeln!(out, "    rate 10 Hz");
    let _ = writeln!(out, "    egos vehicles");
    out.push('\n');

    let r = &c.road;
    comment_lines(&mut out, "    ", &r.notes);
    let mut params = vec![format!("lanes {}", r.lanes), format!("lane_width {} m", num(r.lane_width))];
    params.push(format!("speed_limit {} km/h", num(r.speed_limit_kmh)));
    if r.median > 0.0 {
        params.push(format!("median {} m", num(r.median)));
    }
    if r.shoulder > 0.0 {
        params.push(format!("shoulder {} m", num(r.shoulder)));
    }
    if let Template::Curve { .. } = r.template {
        params.push("radius 250 m".into());
        params.push("angle 30 deg".into());
    }
    // Long enough that every start lies on its lane, with room past the crash.
    let length = match r.template {
        Template::FourWay | Template::TJunction => (far + 20.0).max(60.0),
        Template::Merge => (far + 20.0).max(60.0),
        Template::Straight | Template::Curve { .. } => (2.0 * far + 80.0).max(120.0),
    };
    let default_len = if r.template.has_junction() || r.template == Template::Merge { 60.0 } else { 120.0 };
    if length > default_len {
        params.push(format!("length {} m", num(length.ceil())));
    }
    let _ = writeln!(out, "    road {} {{ {} }}", r.template.name(), params.join("; "));

    for o in &c.objects {
        out.push('\n');
        comment_lines(&mut out, "    ", &o.notes);
        if let Some([x, y, h]) = o.at {
            let _ = writeln!(
                out,
                "    object {}: {} {{ at ({} m, {} m) heading {} deg }}",
                o.name,
                o.kind,
                num2(x),
                num2(y),
                num(h.to_degrees())
            );
            continue;
        }
        // Beside the striker's lane, past the conflict point, clear of the carriageway.
        // Offsets are from `east.out[1]`, the striker's direction's lane nearest the centre line.
        let n = f64::from(r.lanes);
        let (side, off) = match o.side {
            Side::Right => ("right", r.lane_width * (n - 0.5) + r.shoulder + 3.0),
            Side::Left => ("left", r.lane_width * (n + 0.5) + r.median + r.shoulder + 3.0),
        };
        let _ = writeln!(
            out,
            "    object {}: {} {{ at east.out[1], 10 m after center offset {} m {side} }}",
            o.name,
            o.kind,
            num(off)
        );
    }

    for (v, d) in c.vehicles.iter().zip(&ds) {
        out.push('\n');
        comment_lines(&mut out, "    ", &v.notes);
        // A single-vehicle crash into an object: the object stands 10 m past the centre.
        let d = if c.objects.iter().all(|o| o.on_slide) { *d } else { (d - 10.0).max(3.0) };
        let _ = writeln!(out, "    agent {}: {} {{", v.name, v.kind);
        match v.at {
            Some([x, y, h]) => {
                let (x, y, h) = (num2(x), num2(y), num(h.to_degrees()));
                let _ = writeln!(out, "        at ({x} m, {y} m) heading {h} deg");
            }
            None => {
                let _ =
                    writeln!(out, "        at {}.in[{}], {} m before {}", v.arm, v.lane, num(d), landmark(r.template));
            }
        }
        let _ = writeln!(
            out,
            "        speed {} km/h",
            num(if v.manoeuvre == Manoeuvre::Stopped { 0.0 } else { v.speed_kmh })
        );
        let _ = writeln!(out, "        {}", goal(c, v));
        let _ = writeln!(out, "    }}");
    }

    for (i, k) in c.conflicts.iter().enumerate() {
        out.push('\n');
        comment_lines(&mut out, "    ", &k.notes);
        let _ = writeln!(out, "    conflict {{");
        let _ = writeln!(out, "        at_fault {}", k.at_fault);
        let _ = writeln!(out, "        struck {}", k.struck);
        let _ = writeln!(out, "        impact {}", impact_name(k.impact));
        let _ = writeln!(out, "        point {}", k.point.name());
        let _ = writeln!(out, "        at {} s", num(at[i]));
        let _ = writeln!(out, "    }}");
    }
    out.push_str("}\n");
    out
}

/// Whether a latched contact is on the coded sides: the struck sector equals the coded point
/// (a struck fixed object has no coded side: only the striker's face counts), and the
/// striker's contact lies on its coded face (outer 40% of the box along that axis, as the
/// rollout's own tests measure a face).
pub fn on_coded_sides(
    impact: Impact,
    face: Face,
    point: Point,
    struck_side: Point,
    af_local: [f64; 2],
    af_size: [f64; 3],
) -> Result<(), String> {
    if let Some(why) = crate::rollout::wrong_struck_side(impact, point, struck_side) {
        return Err(format!("the contact is on the struck box's {why}"));
    }
    let (x, y) = (af_local[0], af_local[1]);
    let ok = match face {
        Face::Front => x > 0.6 * af_size[0] / 2.0,
        Face::Left => y > 0.6 * af_size[1] / 2.0,
        Face::Right => y < -0.6 * af_size[1] / 2.0,
        Face::Back => x < -0.6 * af_size[0] / 2.0,
    };
    if ok {
        Ok(())
    } else {
        Err(format!("the striker touches with a point at ({x:.2}, {y:.2}) m of its box, not its {}", face.name()))
    }
}

/// Rounds of speed adjustment toward the coded force (clock direction, delta-V).
const FORCE_ROUNDS: usize = 4;

/// Emit, check and roll out a crash whose every contact is staged; keep the first staging whose
/// latched contacts are all on their coded sides and meet their coded force. When the sides are
/// right but a force is not, the speeds `impact::propose` derives from that contact's headings
/// are taken and the staging starts again (at most `FORCE_ROUNDS` times). An error says what
/// the last attempt did. Also the crash with the speeds taken. (`slide::stage` is the entry
/// point: it places what a slide strikes after these are staged.)
pub(super) fn stage_staged(c: &Crash) -> Result<(Staged, Crash), Vec<Diagnostic>> {
    let mut crash = c.clone();
    let mut last = String::new();
    // The first staging whose clocks are met but a closing speed is not: kept, with a warning,
    // when no round meets both (the rollout's staging sets the striker's last-second speed).
    let mut partial: Option<(Staged, Crash)> = None;
    'rounds: for _ in 0..FORCE_ROUNDS {
        let Some((mut staged, tracks, recs)) = stage_sides(&crash, &mut last)? else { break };
        let mut shortfalls = Vec::new();
        for (k, rec) in crash.conflicts.iter().zip(&recs) {
            match super::impact::check(k, &tracks, rec) {
                Ok(()) => {}
                Err(miss) if miss.closing_only => {
                    shortfalls.push(format!("{} into {}: {}", k.at_fault, k.struck, miss.message));
                }
                Err(miss) => {
                    last = format!("{} into {}: {}", k.at_fault, k.struck, miss.message);
                    let Some(speeds) = super::impact::propose(&crash, k, &tracks, rec) else { break 'rounds };
                    set_speeds(&mut crash, &speeds);
                    continue 'rounds;
                }
            }
        }
        if shortfalls.is_empty() {
            return Ok((staged, crash));
        }
        let (k, rec) = crash
            .conflicts
            .iter()
            .zip(&recs)
            .find(|(k, r)| super::impact::check(k, &tracks, r).is_err())
            .expect("a shortfall");
        let speeds = super::impact::propose(&crash, k, &tracks, rec);
        staged.shortfalls = shortfalls;
        partial.get_or_insert((staged, crash.clone()));
        match speeds {
            Some(s) => set_speeds(&mut crash, &s),
            None => break,
        }
    }
    if let Some(p) = partial {
        return Ok(p);
    }
    let k = &c.conflicts[0];
    let what = if c.conflicts.len() == 1 {
        format!("{}'s {} into {}'s {} side", k.at_fault, k.face.name(), k.struck, k.point.name())
    } else {
        format!("its {} contacts", c.conflicts.len())
    };
    Err(vec![
        Diagnostic::error("E0805", format!("case {}: rocc could not stage {what}: {last}", c.id))
            .help("nothing is written for this case; `rocc explain E0805` lists what the staging can and cannot do"),
    ])
}

/// Take the speeds the coded force asks, said in each vehicle's notes.
fn set_speeds(c: &mut Crash, speeds: &[(String, f64)]) {
    const NOTE: &str = "speed at contact set by the coded force";
    for (name, kmh) in speeds {
        if let Some(v) = c.vehicles.iter_mut().find(|v| &v.name == name) {
            v.speed_kmh = (kmh * 10.0).round() / 10.0;
            v.notes.retain(|n| !n.starts_with(NOTE));
            v.notes.push(format!("{NOTE} (clock direction, delta-V): {} km/h", num(v.speed_kmh)));
        }
    }
}

type Rolled = (Staged, crate::rollout::Tracks, Vec<crate::rollout::ImpactRecord>);

/// The first staging whose latched contacts are all on their coded sides, with its tracks and
/// one impact per conflict (time order); `None` (and `last` saying why) when none is.
fn stage_sides(c: &Crash, last: &mut String) -> Result<Option<Rolled>, Vec<Diagnostic>> {
    let tries = LAGS.iter().flat_map(|&lag| TIMES.iter().map(move |&t| (t, lag)));
    for (t, lag) in tries {
        let st = Staging { t_impact: t, lag };
        let (text, tracks) = match roll(c, st)? {
            Ok((text, f)) => (text, f.tracks),
            Err(m) => {
                *last = m;
                continue;
            }
        };
        match contacts_on_sides(c, &tracks) {
            Ok(recs) => {
                let first = &recs[0];
                let staged = Staged {
                    text,
                    staging: st,
                    frame: first.frame,
                    time: first.frame as f64 / tracks.rate,
                    struck_side: first.struck_side,
                    shortfalls: Vec::new(),
                };
                return Ok(Some((staged, tracks, recs)));
            }
            Err(m) => *last = format!("{m} (impact at {} s)", num(t)),
        }
    }
    Ok(None)
}

/// The text of `c` under `st` and its front (the checked scenario, the rolled-out tracks); the
/// inner error says why the front refused it. A text the checker refuses is a bug in the
/// importer, reported as one.
pub(super) fn roll(c: &Crash, st: Staging) -> Result<Result<(String, crate::compile::Front), String>, Vec<Diagnostic>> {
    let text = emit(c, st);
    let mut sources = SourceMap::default();
    let name = format!("{}.scn", c.file_stem());
    let scen = match crate::check::check_text(&name, &text, Path::new("."), &mut sources) {
        Ok(s) => s,
        Err(d) => {
            // The emitter writes only what the checker accepts: a failure here is a bug,
            // reported with the checker's own words rather than hidden.
            let what: Vec<String> = d.iter().map(|x| format!("{}: {}", x.code, x.message)).collect();
            return Err(vec![
                Diagnostic::error(
                    "E0805",
                    format!("case {}: the generated scenario does not check: {}", c.id, what.join("; ")),
                )
                .help("this is a bug in the importer; please report it with the case file"),
            ]);
        }
    };
    Ok(match crate::compile::front(scen, None) {
        Ok(f) => Ok((text, f)),
        Err(d) => Err(d.iter().map(|x| format!("{}: {}", x.code, x.message)).collect::<Vec<_>>().join("; ")),
    })
}

/// One latched impact per conflict, each deep enough and on its coded sides.
pub(super) fn contacts_on_sides(
    c: &Crash,
    t: &crate::rollout::Tracks,
) -> Result<Vec<crate::rollout::ImpactRecord>, String> {
    let mut out = Vec::new();
    for (i, k) in c.conflicts.iter().enumerate() {
        let pair = format!("{} into {}", k.at_fault, k.struck);
        let rec = t.impacts.iter().find(|r| r.conflict == i).ok_or_else(|| format!("{pair}: no contact"))?;
        if rec.depth < crate::rollout::MIN_DEPTH {
            return Err(format!("{pair}: only a {:.2} m graze", rec.depth));
        }
        let size = t.agents[rec.at_fault].size;
        on_coded_sides(k.impact, k.face, k.point, rec.struck_side, rec.at_fault_local, size)
            .map_err(|m| format!("{pair}: {m}"))?;
        out.push(rec.clone());
    }
    Ok(out)
}
