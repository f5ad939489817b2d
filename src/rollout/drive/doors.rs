//! An open door of what stands in the lane (a parked car's, `rollout/body.rs`) is an obstacle of
//! its own to a vehicle passing by: a cyclist eases aside round it, or, where it swings open too
//! late for that, rides into it (scenarios/rare/dooring.scn).

use crate::place::Pose;
use crate::rollout::agent::Blocking;
use crate::rollout::body::door_box;
use crate::rollout::frame::Sim;
use crate::rollout::path::Foot;
use glam::DVec2;

impl Sim<'_, '_> {
    /// Add to `seen` each door of blocker `j` open at frame `f`, as vehicle `i` sees it from its
    /// route; `room` is the paving round `j` as offsets on `i`'s route (the door's too).
    pub(crate) fn open_doors(&self, i: usize, j: usize, f: usize, room: (f64, f64), seen: &mut Vec<Blocking>) {
        let (a, st, b, o) = (&self.actors[i], &self.cur[i], &self.actors[j], &self.cur[j]);
        let pose = Pose { x: o.pos.x, y: o.pos.y, yaw: o.yaw };
        for (door, deg) in &b.doors {
            let Some(&deg) = deg.get(f).or(deg.last()) else { continue };
            let Some((p, [l, w, _])) = door_box(*door, deg, [2.0 * b.hl, 2.0 * b.hw, 1.0], pose) else { continue };
            let pos = DVec2::new(p.x, p.y);
            let ahead = (pos - st.pos).dot(self.facts.dirs[i]);
            let Foot { s: sj, d: lj, beyond, dir: th } = a.path.frenet_dir(pos, st.s + ahead);
            let d = DVec2::from_angle(p.yaw);
            let (cr, sr) = (d.dot(th), th.perp_dot(d));
            let ext_lon = 0.5 * (l * cr.abs() + w * sr.abs());
            let ext_lat = 0.5 * (l * sr.abs() + w * cr.abs());
            if beyond > 0.5 || sj + ext_lon < st.s - a.hl - 1.0 {
                continue;
            }
            seen.push(Blocking { sj, lj, ext_lon, ext_lat, lo: room.0, hi: room.1, v: 0.0 });
        }
    }
}
