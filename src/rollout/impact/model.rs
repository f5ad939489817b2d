//! The planar impulse-momentum impact of two rigid boxes: the model of crash reconstruction
//! (Brach's planar impact mechanics). One impulse at the contact point, its normal part set by
//! the coefficient of restitution, its tangential part the one that stops the sliding of the two
//! surfaces past each other where the inter-body friction can supply it (sticking), else the
//! friction limit against the slip (sliding). Linear and angular momentum are conserved exactly;
//! energy is lost, never gained.

use glam::DVec2;

/// One body at the instant of impact. An immovable body (an object, a replayed track, a held
/// wreck) has `inv_mass` and `inv_inertia` 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Body {
    pub centre: DVec2,
    pub vel: DVec2,
    /// Yaw rate, rad/s (counter-clockwise positive).
    pub omega: f64,
    /// 1 / mass, 1/kg.
    pub inv_mass: f64,
    /// 1 / yaw moment of inertia, 1/(kg m^2).
    pub inv_inertia: f64,
}

/// What the impact sets: the impulse on `b` (the opposite on `a`), N s, and both bodies' new
/// velocities and yaw rates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Outcome {
    pub impulse: DVec2,
    pub a: (DVec2, f64),
    pub b: (DVec2, f64),
    /// The surfaces stuck together tangentially (false: they slid, friction at its limit).
    pub sticking: bool,
}

/// The coefficients of one impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coefficients {
    /// Coefficient of restitution, 0..1.
    pub restitution: f64,
    /// Inter-body friction, the largest ratio of tangential to normal impulse.
    pub friction: f64,
}

/// Resolve the impact of `a` and `b` at `point`, `normal` the unit contact normal pointing from
/// `a` into `b`: the normal relative velocity after is the restitution's rebound, or `bias` if
/// that is more (two overlapping bodies separate within their contact's window). Bodies already
/// separating at `bias` or faster exchange no impulse.
pub(crate) fn resolve(a: &Body, b: &Body, point: DVec2, normal: DVec2, k: Coefficients, bias: f64) -> Outcome {
    let (ra, rb) = (point - a.centre, point - b.centre);
    let vel_at = |body: &Body, r: DVec2| body.vel + r.perp() * body.omega;
    // Velocity of b's contact point relative to a's.
    let rel = vel_at(b, rb) - vel_at(a, ra);
    let tangent = normal.perp();
    let (vn, vt) = (rel.dot(normal), rel.dot(tangent));
    let keep = Outcome { impulse: DVec2::ZERO, a: (a.vel, a.omega), b: (b.vel, b.omega), sticking: true };
    if vn >= bias.max(0.0) || a.inv_mass + b.inv_mass <= 0.0 {
        return keep;
    }
    // How an impulse J on b (and -J on a) changes the relative contact velocity: K J.
    let k_of = |r: DVec2, inv_i: f64| {
        let p = r.perp();
        [[p.x * p.x * inv_i, p.x * p.y * inv_i], [p.y * p.x * inv_i, p.y * p.y * inv_i]]
    };
    let (ka, kb) = (k_of(ra, a.inv_inertia), k_of(rb, b.inv_inertia));
    let m = a.inv_mass + b.inv_mass;
    let kk = [[m + ka[0][0] + kb[0][0], ka[0][1] + kb[0][1]], [ka[1][0] + kb[1][0], m + ka[1][1] + kb[1][1]]];
    let apply = |j: DVec2| DVec2::new(kk[0][0] * j.x + kk[0][1] * j.y, kk[1][0] * j.x + kk[1][1] * j.y);
    // Sticking: the normal velocity reversed by the restitution, the tangential one brought to 0.
    let dvn = (-k.restitution * vn).max(bias) - vn;
    let want = normal * dvn - tangent * vt;
    let det = kk[0][0] * kk[1][1] - kk[0][1] * kk[1][0];
    let stick = DVec2::new(kk[1][1] * want.x - kk[0][1] * want.y, kk[0][0] * want.y - kk[1][0] * want.x) / det;
    let (jn, jt) = (stick.dot(normal), stick.dot(tangent));
    let (impulse, sticking) = if jt.abs() <= k.friction * jn {
        (stick, true)
    } else {
        // Sliding: friction at its limit against the slip, the normal impulse from restitution.
        let dir = normal - tangent * (k.friction * vt.signum());
        let jn = dvn / apply(dir).dot(normal);
        (dir * jn.max(0.0), false)
    };
    let spin = |r: DVec2, j: DVec2| r.perp_dot(j);
    Outcome {
        impulse,
        a: (a.vel - impulse * a.inv_mass, a.omega - spin(ra, impulse) * a.inv_inertia),
        b: (b.vel + impulse * b.inv_mass, b.omega + spin(rb, impulse) * b.inv_inertia),
        sticking,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn car(x: f64, y: f64, vx: f64, vy: f64) -> Body {
        let (m, l, w) = (1500.0, 4.6, 1.8);
        Body {
            centre: DVec2::new(x, y),
            vel: DVec2::new(vx, vy),
            omega: 0.0,
            inv_mass: 1.0 / m,
            inv_inertia: 12.0 / (m * (l * l + w * w)),
        }
    }

    fn energy(b: &Body, (v, w): (DVec2, f64)) -> f64 {
        let (m, i) = (1.0 / b.inv_mass, 1.0 / b.inv_inertia);
        0.5 * m * v.length_squared() + 0.5 * i * w * w
    }

    const K: Coefficients = Coefficients { restitution: 0.1, friction: 0.5 };

    /// A central rear-end of equal masses: the textbook result, v' = (v1 + v2)/2 -+ e (v1 - v2)/2.
    #[test]
    fn central_rear_end_of_equal_masses() {
        let (a, b) = (car(0.0, 0.0, 10.0, 0.0), car(4.6, 0.0, 2.0, 0.0));
        let o = resolve(&a, &b, DVec2::new(2.3, 0.0), DVec2::X, K, 0.0);
        assert!((o.a.0.x - (6.0 - 0.4)).abs() < 1e-9 && (o.b.0.x - (6.0 + 0.4)).abs() < 1e-9, "{o:?}");
        assert!(o.a.1.abs() < 1e-12 && o.b.1.abs() < 1e-12 && o.sticking);
    }

    /// Off-centre and oblique impacts conserve linear and angular momentum, lose energy, and
    /// respect the friction cone; an immovable body takes the whole impulse.
    #[test]
    fn momentum_is_conserved_and_energy_lost() {
        let cases = [
            (car(0.0, 0.0, 12.0, 0.0), car(3.5, 1.2, 0.0, 0.0), DVec2::new(2.3, 0.6), DVec2::X),
            (car(0.0, 0.0, 15.0, 1.0), car(2.0, 3.0, 0.0, -8.0), DVec2::new(1.5, 1.0), DVec2::Y),
            (car(0.0, 0.0, 20.0, 0.0), car(4.0, 0.5, -15.0, 0.0), DVec2::new(2.2, 0.9), DVec2::X),
        ];
        for (a, b, p, n) in cases {
            let o = resolve(&a, &b, p, n, K, 0.0);
            let lin = (o.a.0 - a.vel) / a.inv_mass + (o.b.0 - b.vel) / b.inv_mass;
            assert!(lin.length() < 1e-6, "linear momentum changed by {lin}");
            let ang = |c: DVec2, v: DVec2, w: f64, body: &Body| c.perp_dot(v) / body.inv_mass + w / body.inv_inertia;
            let before = ang(a.centre, a.vel, a.omega, &a) + ang(b.centre, b.vel, b.omega, &b);
            let after = ang(a.centre, o.a.0, o.a.1, &a) + ang(b.centre, o.b.0, o.b.1, &b);
            assert!((before - after).abs() < 1e-6 * before.abs().max(1.0), "angular momentum {before} -> {after}");
            let (e0, e1) =
                (energy(&a, (a.vel, a.omega)) + energy(&b, (b.vel, b.omega)), energy(&a, o.a) + energy(&b, o.b));
            assert!(e1 <= e0 + 1e-6, "energy grew {e0} -> {e1}");
            let (jn, jt) = (o.impulse.dot(n), o.impulse.dot(n.perp()));
            assert!(jn > 0.0 && jt.abs() <= K.friction * jn + 1e-9, "{jn} {jt}");
        }
        let mut pole = car(3.0, 0.0, 0.0, 0.0);
        (pole.inv_mass, pole.inv_inertia) = (0.0, 0.0);
        let a = car(0.0, 0.0, 10.0, 0.0);
        let o = resolve(&a, &pole, DVec2::new(2.3, 0.0), DVec2::X, K, 0.0);
        assert_eq!(o.b, (pole.vel, 0.0));
        assert!((o.a.0.x + 1.0).abs() < 1e-9, "bounces back at e v: {:?}", o.a);
    }

    /// A bias larger than the rebound sets the parting speed, with momentum still conserved;
    /// a pair already parting that fast exchanges nothing.
    #[test]
    fn bias_sets_the_least_parting_speed() {
        let (a, b) = (car(0.0, 0.0, 10.0, 0.0), car(4.6, 0.0, 8.0, 0.0));
        let o = resolve(&a, &b, DVec2::new(2.3, 0.0), DVec2::X, K, 1.5);
        assert!((o.b.0.x - o.a.0.x - 1.5).abs() < 1e-9, "{o:?}");
        assert!((o.a.0.x + o.b.0.x - 18.0).abs() < 1e-9);
        let (a, b) = (car(0.0, 0.0, 8.0, 0.0), car(4.6, 0.0, 10.0, 0.0));
        assert_eq!(resolve(&a, &b, DVec2::new(2.3, 0.0), DVec2::X, K, 1.5).impulse, DVec2::ZERO);
    }

    /// Bodies already moving apart exchange nothing.
    #[test]
    fn separating_bodies_exchange_nothing() {
        let (a, b) = (car(0.0, 0.0, 1.0, 0.0), car(4.6, 0.0, 3.0, 0.0));
        assert_eq!(resolve(&a, &b, DVec2::new(2.3, 0.0), DVec2::X, K, 0.0).impulse, DVec2::ZERO);
    }
}
