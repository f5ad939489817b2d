//! The coded force of the staged event: the clock direction of the principal force on each
//! vehicle of the pair (CDC) and the closing speed its coded delta-V implies, by the momentum
//! model of `ciren/impact.rs` with masses from the record's curb weights, else class priors.

use super::ctx::Ctx;
use crate::ciren::crash::{ClockDesc, Closing, ConflictDesc, Crash};
use crate::ciren::emit::num;
use crate::ciren::impact::{closing_kmh, prior_kg};

/// A vehicle's mass (kg) and where it came from: the coded curb weight, else the kind's prior.
fn mass(cx: &Ctx, crash: &Crash, name: &str) -> Option<(f64, String)> {
    let v = crash.vehicle(name)?;
    let n: u32 = name.trim_start_matches('v').parse().ok()?;
    let curb = cx.case.vehicles.iter().find(|c| c.number == n).and_then(|c| c.curb_weight.as_ref());
    if let Some(kg) = curb.and_then(|c| c.value.parse::<f64>().ok()).filter(|kg| (300.0..=40_000.0).contains(kg)) {
        return Some((kg, format!("V{n} CurbWeight {} kg", num(kg))));
    }
    let kg = prior_kg(&v.kind);
    Some((kg, format!("V{n} {} prior {} kg", v.kind, num(kg))))
}

/// Fill conflict `i`'s clocks and closing speed from the CDC rows of `event`.
pub(super) fn annotate(cx: &Ctx, crash: &mut Crash, i: usize, event: u32) {
    let k = crash.conflicts[i].clone();
    let pair = [k.at_fault.clone(), k.struck.clone()];
    let rows: Vec<_> =
        cx.case.cdc.iter().filter(|r| r.event == event && pair.contains(&format!("v{}", r.vehicle))).collect();
    let mut out: ConflictDesc = k;
    for r in &rows {
        if let Some(h) = r.clock {
            out.clocks.push(ClockDesc { vehicle: format!("v{}", r.vehicle), hour: h });
            out.notes.push(format!(
                "V{}'s CDC ClockDirection {h}: the principal force comes from its {h} o'clock (within one hour at contact).",
                r.vehicle
            ));
        }
    }
    // The first row with a known total delta-V sets the closing speed.
    for r in &rows {
        let Some(dv) = r.delta_v.as_ref() else { continue };
        let Some(x) = dv.value.parse::<f64>().ok().filter(|x| *x > 0.0 && *x < 250.0) else { continue };
        let dv_kmh = if dv.unit.eq_ignore_ascii_case("mph") { x * 1.609_344 } else { x };
        let me = format!("v{}", r.vehicle);
        let other = if me == pair[0] { &pair[1] } else { &pair[0] };
        let Some((m_me, m_cite)) = mass(cx, crash, &me) else { continue };
        let other_mass = mass(cx, crash, other);
        let c = closing_kmh(dv_kmh, m_me, other_mass.as_ref().map(|m| m.0));
        let others = match &other_mass {
            Some((_, cite)) => format!("{m_cite}, {cite}"),
            None => format!("{m_cite}, {other} fixed"),
        };
        out.notes.push(format!(
            "V{}'s delta-V {} km/h ({others}): closing speed {} km/h at contact (momentum, common velocity after).",
            r.vehicle,
            num(dv_kmh),
            num(c)
        ));
        out.closing = Some(Closing { kmh: c });
        break;
    }
    crash.conflicts[i] = out;
}
