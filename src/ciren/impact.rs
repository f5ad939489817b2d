//! The force of a staged impact: what a coded clock direction and delta-V ask of the contact,
//! measured on the rolled-out boxes, and the speeds that bring a staging closer to it.
//!
//! The model is the momentum balance of crash reconstruction with a common velocity after
//! contact (a plastic impact): a vehicle of mass `m` struck by a body of mass `M` changes
//! velocity by `dv = M / (m + M) * closing`, so `closing = dv * (m + M) / M`; a fixed object is
//! of unbounded mass (`closing = dv`). The principal force on a vehicle points along the
//! relative velocity of the other body, so it comes from where the vehicle moves relative to
//! that body: the clock of `v_self - v_other` in the vehicle's frame (12 ahead, 3 the right).

use super::crash::{ConflictDesc, Crash, Manoeuvre};
use crate::rollout::{ImpactRecord, Tracks};
use glam::DVec2;

/// A kind's mass (kg) when the record codes no curb weight: typical curb weights of the class.
pub fn prior_kg(kind: &str) -> f64 {
    match kind {
        "motorcycle" => 250.0,
        "hatchback" => 1200.0,
        "sedan" => 1450.0,
        "police_car" => 1800.0,
        "suv" => 1900.0,
        "van" => 2000.0,
        "pickup_truck" => 2100.0,
        "ambulance" => 3500.0,
        "truck" => 8000.0,
        "bus" => 12_000.0,
        "semi_truck" | "fire_truck" => 15_000.0,
        _ => 1500.0,
    }
}

/// Closing speed (km/h) of an impact in which a vehicle of mass `m_self` changed velocity by
/// `dv_kmh`; `m_other` is `None` for a fixed object.
pub fn closing_kmh(dv_kmh: f64, m_self: f64, m_other: Option<f64>) -> f64 {
    match m_other {
        Some(m) => dv_kmh * (m_self + m) / m,
        None => dv_kmh,
    }
}

/// How far a measured clock direction may lie from the coded one, hours. The acceptance is a
/// little inside the one hour the documentation promises, so a measurement by other means
/// (tests/ciren.rs) agrees.
const CLOCK_TOLERANCE_H: f64 = 0.9;
/// How far the measured closing speed may lie from the delta-V's, as a fraction.
const CLOSING_TOLERANCE: f64 = 0.2;
/// Speed bounds of a moving vehicle whose speed the force sets, km/h.
const MIN_KMH: f64 = 5.0;
const MAX_KMH: f64 = 130.0;

/// Velocity (m/s, world) of agent `i` over the frame leading into frame `f`.
pub fn velocity(t: &Tracks, i: usize, f: usize) -> DVec2 {
    let (p0, p1) = (t.poses[i][f.saturating_sub(1)], t.poses[i][f]);
    DVec2::new(p1.x - p0.x, p1.y - p0.y) * t.rate
}

/// The clock direction (0.5..12.5) the force on agent `a` from agent `b` comes from at frame `f`.
pub fn clock_of(t: &Tracks, a: usize, b: usize, f: usize) -> f64 {
    let rel = (velocity(t, a, f) - velocity(t, b, f)).rotate(DVec2::from_angle(-t.poses[a][f.saturating_sub(1)].yaw));
    let h = (-rel.y.atan2(rel.x).to_degrees()).rem_euclid(360.0) / 30.0;
    if h < 0.5 { h + 12.0 } else { h }
}

/// Distance between two clock directions, hours (0..6).
pub fn clock_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(12.0);
    d.min(12.0 - d)
}

fn agent(t: &Tracks, name: &str) -> Option<usize> {
    t.agents.iter().position(|a| a.name == name)
}

/// How a contact misses its coded force.
#[derive(Clone, Debug, PartialEq)]
pub struct Miss {
    /// The clock directions are met; only the closing speed is off.
    pub closing_only: bool,
    pub message: String,
}

/// Whether the contact meets the conflict's coded force; the error says how it misses.
pub fn check(k: &ConflictDesc, t: &Tracks, rec: &ImpactRecord) -> Result<(), Miss> {
    let f = rec.frame;
    for cl in &k.clocks {
        let other = if cl.vehicle == k.at_fault { &k.struck } else { &k.at_fault };
        let (Some(a), Some(b)) = (agent(t, &cl.vehicle), agent(t, other)) else { continue };
        let h = clock_of(t, a, b, f);
        if clock_gap(h, f64::from(cl.hour)) > CLOCK_TOLERANCE_H {
            let message = format!("the force on {} comes from {h:.1} o'clock, coded {} o'clock", cl.vehicle, cl.hour);
            return Err(Miss { closing_only: false, message });
        }
    }
    if let Some(cl) = &k.closing {
        let got = (velocity(t, rec.at_fault, f) - velocity(t, rec.struck, f)).length() * 3.6;
        if (got - cl.kmh).abs() > CLOSING_TOLERANCE * cl.kmh {
            let message = format!("the closing speed is {got:.0} km/h, the coded delta-V asks {:.0}", cl.kmh);
            return Err(Miss { closing_only: true, message });
        }
    }
    Ok(())
}

/// Speeds (km/h, by vehicle name) that turn the measured relative velocity at `rec` toward the
/// coded clock direction and closing speed, given the headings the staging met with; `None`
/// when no bounded speeds do. Offsets up to 0.75 h from the coded hour are tried, nearest first.
pub fn propose(c: &Crash, k: &ConflictDesc, t: &Tracks, rec: &ImpactRecord) -> Option<Vec<(String, f64)>> {
    let f = rec.frame;
    let (a_name, b_name, hour) = match k.clocks.first() {
        Some(cl) if cl.vehicle == k.at_fault => (k.at_fault.clone(), k.struck.clone(), Some(cl.hour)),
        Some(cl) => (k.struck.clone(), k.at_fault.clone(), Some(cl.hour)),
        None => (k.struck.clone(), k.at_fault.clone(), None),
    };
    let (a, b) = (agent(t, &a_name)?, agent(t, &b_name)?);
    let unit = |i: usize| DVec2::from_angle(t.poses[i][f.saturating_sub(1)].yaw);
    let (ua, ub) = (unit(a), unit(b));
    let (va, vb) = (velocity(t, a, f), velocity(t, b, f));
    let cur = va - vb;
    let mag = k.closing.as_ref().map_or(cur.length(), |cl| cl.kmh / 3.6);
    let moves = |n: &str| c.vehicle(n).is_some_and(|v| v.manoeuvre != Manoeuvre::Stopped);
    let (ma, mb) = (moves(&a_name), moves(&b_name));
    let dirs: Vec<DVec2> = match hour {
        Some(h) => [0.0, 0.25, -0.25, 0.5, -0.5, 0.75, -0.75]
            .iter()
            .map(|d| ua.rotate(DVec2::from_angle(-(f64::from(h) + d) * std::f64::consts::FRAC_PI_6)))
            .collect(),
        None if cur.length() > 1e-6 => vec![cur.normalize()],
        None => return None,
    };
    let ok = |s: f64| (MIN_KMH..=MAX_KMH).contains(&(s * 3.6));
    for d in dirs {
        let w = d * mag;
        let (sa, sb) = (va.dot(ua), vb.dot(ub));
        let det = ua.perp_dot(-ub);
        let (sa, sb) = if ma && mb && det.abs() > 0.15 {
            // s_a ua - s_b ub = w, by Cramer's rule.
            (w.perp_dot(-ub) / det, ua.perp_dot(w) / det)
        } else if ma {
            ((w + vb).dot(ua), sb)
        } else if mb {
            (sa, (va - w).dot(ub))
        } else {
            return None;
        };
        if (!ma || ok(sa)) && (!mb || ok(sb)) {
            let mut out = Vec::new();
            if ma {
                out.push((a_name.clone(), sa * 3.6));
            }
            if mb {
                out.push((b_name.clone(), sb * 3.6));
            }
            return Some(out);
        }
    }
    None
}
