//! Tracks on the map: keyframes in lane coordinates get world poses (`resolve_keys`), then each
//! track is checked like any motion once its box is known: the feasibility limits of its kind
//! (`check::track`, E0131-E0134) and, for a vehicle on a map, every keyframe on a lane, the
//! shoulder or the junction (E0210). Each error names the keyframe.

use super::surface::Surfaces;
use crate::check::scenario::{Class, Keyframe, Motion};
use crate::check::track::{Violation, first_violation, limits};
use crate::diag::Diagnostic;
use crate::road::Map;
use crate::sample::{Concrete, ConcreteAgent};
use glam::DVec2;

/// Give every keyframe written in lane coordinates (`2 s: west.in[1], 20 m before center`) its
/// world pose on `map`; one beyond its lane's end is E0203 at the keyframe.
pub fn resolve_keys(c: &mut Concrete, map: &Map) -> Result<(), Vec<Diagnostic>> {
    let mut errs = Vec::new();
    for a in &mut c.agents {
        for k in a.track.iter_mut().flatten() {
            let Some(at) = &k.at else { continue };
            match super::resolve::pose(map, at, None) {
                Ok(p) => (k.x, k.y, k.yaw) = (p.x, p.y, p.yaw),
                Err(miss) => errs.push(super::off_road(&miss, &format!("a keyframe of `{}`", a.name), k.span)),
            }
        }
    }
    if errs.is_empty() { Ok(()) } else { Err(errs) }
}

/// The first infeasible step of `a`'s track and every keyframe of a moving vehicle off the road.
pub(super) fn check(map: &Map, a: &ConcreteAgent, keys: &[Keyframe]) -> Vec<Diagnostic> {
    let mut errs = Vec::new();
    if let Some(v) = first_violation(keys, &limits(a.motion, a.class), a.size[0]) {
        errs.push(infeasible(a, keys, &v));
    }
    // A road-less scene (imported recorded tracks) has no surface to hold them to.
    if a.class == Class::Vehicle && a.motion == Motion::Vehicle && !map.lanes.is_empty() {
        for (i, k) in keys.iter().enumerate() {
            let s = Surfaces::at(map, DVec2::new(k.x, k.y));
            if !(s.lane || s.shoulder || s.junction) {
                errs.push(
                    Diagnostic::error(
                        "E0210",
                        format!(
                            "`{}`'s track leaves the road: keyframe {} ({} s) is {} at ({:.1}, {:.1})",
                            a.name,
                            i + 1,
                            k.t,
                            s.describe(),
                            k.x,
                            k.y
                        ),
                    )
                    .label(k.span, s.describe())
                    .help("a vehicle drives on a lane, the shoulder or the junction: move the keyframe onto one"),
                );
                break;
            }
        }
    }
    errs
}

fn infeasible(a: &ConcreteAgent, keys: &[Keyframe], v: &Violation) -> Diagnostic {
    let lim = limits(a.motion, a.class);
    let class = a.class.name();
    let dt = keys[v.key].t - keys[v.from].t;
    let (what, measured, limit, help) = match v.code {
        "E0131" => (
            "speed",
            format!("{:.1} m/s ({:.0} km/h)", v.measured, v.measured * 3.6),
            format!("{:.1} m/s", v.limit),
            format!("a {class} moves at most {:.0} km/h: spread the keyframes out in time", v.limit * 3.6),
        ),
        "E0132" => (
            "acceleration",
            format!("{:.1} m/s^2", v.measured),
            format!("{:.1} m/s^2", v.limit),
            format!(
                "a {class} speeds up, brakes or corners at most {:.1} m/s^2: smooth the speed between these keyframes",
                v.limit
            ),
        ),
        "E0133" => (
            "yaw rate",
            format!("{:.0} deg/s", v.measured.to_degrees()),
            format!("{:.0} deg/s", v.limit.to_degrees()),
            if lim.wheeled {
                "a vehicle turns only while it moves, no tighter than its turning radius and no faster than its grip allows at that speed".to_string()
            } else {
                "turn the heading more slowly, or add time between the keyframes".to_string()
            },
        ),
        _ => (
            "sideways slip",
            format!("{:.0} deg off its heading", v.measured.to_degrees()),
            format!("{:.0} deg", v.limit.to_degrees()),
            "a vehicle moves along its heading, forwards or in reverse: give the keyframe the heading of its travel"
                .to_string(),
        ),
    };
    Diagnostic::error(v.code, format!("`{}`'s track is infeasible: {what} {measured} exceeds {limit}", a.name))
        .label(keys[v.key].span, format!("{what} {measured} over {dt:.2} s"))
        .label(keys[v.from].span, "from this keyframe")
        .help(help)
}
