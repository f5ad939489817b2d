//! Car-following laws: IDM's free-road and interaction terms, the stopping law that lands on a
//! mark, and Gipps's safe speed behind a leader.

use crate::rollout::Limits;
use crate::rollout::frame::Sim;

/// Clearance kept to where a leader could stop (`Sim::safe_acc`), m.
pub(crate) const SAFE_MARGIN: f64 = 0.5;

pub(crate) fn idm_free(v: f64, v0: f64, lim: Limits, dt: f64) -> f64 {
    if v0 < 0.05 {
        return -(v / dt).min(lim.brake);
    }
    (lim.accel * (1.0 - (v / v0).powi(4))).max(-lim.brake)
}

pub(crate) fn idm_interaction(v: f64, v_lead: f64, gap: f64, s0: f64, lim: Limits) -> f64 {
    let s_star = s0 + (v * lim.headway + v * (v - v_lead) / (2.0 * (lim.accel * lim.brake).sqrt())).max(0.0);
    let g = gap.max(0.05);
    lim.accel * (1.0 - (s_star / g) * (s_star / g))
}

/// Constant deceleration that halts exactly `rem` metres ahead, engaged once it reaches half the
/// comfortable braking or the mark is near (so approach is at speed, and the stop lands on it).
pub(crate) fn stop_law(v: f64, rem: f64, lim: Limits, dt: f64) -> f64 {
    if rem <= 0.05 {
        return -v / dt;
    }
    let b = v * v / (2.0 * rem);
    // Close to the mark, always: car-following alone only creeps up on a standstill gap.
    if b >= 0.5 * lim.brake || rem < 2.0 { -b } else { f64::INFINITY }
}

impl Sim<'_, '_> {
    /// Gipps's safe speed behind leader `j`, `gap` ahead at `v_lon` along our path, as an
    /// acceleration: after this step we must still be able to stop at our emergency braking
    /// behind the point where the leader stops at its own. A conflict agent whose striker has
    /// set off may instead be stopped dead by the crash latch, but only on touching its
    /// partner: it stops no sooner than the clearance between the two. With every agent inside
    /// its limits this keeps the overlap safety net from ever braking anyone harder than that.
    pub(crate) fn safe_acc(&self, i: usize, j: usize, gap: f64, v_lon: f64, t: f64) -> f64 {
        let (a, st, dt) = (&self.actors[i], &self.cur[i], self.dt);
        let b = a.lim.brake_max;
        let lead = &self.actors[j];
        let mut lead_stop = if v_lon <= 0.0 { 0.0 } else { v_lon * v_lon / (2.0 * lead.lim.brake_max) };
        // A vehicle coming toward us in our band (a bus turning across the corner our own turn
        // swings over) closes the gap while both brake: it comes on by its own emergency stop,
        // taken a step late. Counted as standing, it closed 0.7 m a frame on a bus that then
        // had to stop at 13 m/s2. Staged pairs and their partners keep their plans.
        if v_lon < -0.5 && lead.vehicle && !lead.in_conflict && !a.in_conflict {
            lead_stop = v_lon * dt - v_lon * v_lon / (2.0 * lead.lim.brake_max);
        }
        if lead.in_conflict
            && let Some(p) = self.crash_partner(j, t)
        {
            let clearance = self.cur[j].pos.distance(self.cur[p].pos) - lead.radius - self.actors[p].radius;
            lead_stop = lead_stop.min(clearance.max(0.0));
        }
        // Room left after this step's own travel at the current speed (the half step at `v`).
        let room = gap - SAFE_MARGIN + lead_stop - 0.5 * st.v * dt;
        let v_safe = if room <= 0.0 { 0.0 } else { 0.5 * (-b * dt + (b * b * dt * dt + 8.0 * b * room).sqrt()) };
        (v_safe - st.v) / dt
    }
}
