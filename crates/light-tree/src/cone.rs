//! Orientation cones (axis, θo, θe) after Conty Estevez & Kulla 2018: union and the
//! orientation measure M_Ω used by the SAOH.

use glam::{Quat, Vec3};
use std::f32::consts::{FRAC_PI_2, PI};

/// Slack (radians) added to a merged cone's θo so that rounding never makes it
/// non-conservative.
const UNION_SLACK: f32 = 1e-5;

/// An orientation bound: every emitting normal lies within `theta_o` of `axis`, and light
/// leaves each normal at most `theta_e` away from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Central direction of the bounded normals (unit length).
    pub axis: Vec3,
    /// Half-angle in radians around `axis` holding every normal: [0, π], π meaning any
    /// direction; negative only for [`Cone::EMPTY`].
    pub theta_o: f32,
    /// Largest angle in radians between emitted light and its normal, in [0, π].
    pub theta_e: f32,
}

impl Cone {
    /// The identity of [`Cone::union`]; `theta_o < 0` marks it.
    pub const EMPTY: Cone = Cone {
        axis: Vec3::Z,
        theta_o: -1.0,
        theta_e: 0.0,
    };

    /// Whether this is the empty cone (bounds no normal at all), i.e. `theta_o < 0`.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.theta_o < 0.0
    }

    /// Smallest cone (in the E&K sense) bounding both; `EMPTY` is the identity, so a
    /// union with it returns the other cone bit for bit.
    #[inline]
    pub fn union(a: Cone, b: Cone) -> Cone {
        if a.is_empty() {
            return b;
        }
        if b.is_empty() {
            return a;
        }
        let (a, b) = if a.theta_o >= b.theta_o {
            (a, b)
        } else {
            (b, a)
        };
        let theta_e = a.theta_e.max(b.theta_e);
        if a.theta_o >= PI {
            return Cone {
                axis: a.axis,
                theta_o: PI,
                theta_e,
            };
        }
        if a.axis == b.axis {
            return Cone { theta_e, ..a };
        }
        Self::union_slow(a, b, theta_e)
    }

    /// General case of `union`: `a.theta_o >= b.theta_o`, `a` not the full sphere.
    #[inline(never)]
    fn union_slow(a: Cone, b: Cone, theta_e: f32) -> Cone {
        let theta_d = angle_between(a.axis, b.axis);
        if (theta_d + b.theta_o).min(PI) <= a.theta_o {
            return Cone {
                axis: a.axis,
                theta_o: a.theta_o,
                theta_e,
            };
        }
        let theta_o = 0.5 * (a.theta_o + theta_d + b.theta_o) + UNION_SLACK;
        let full = Cone {
            axis: a.axis,
            theta_o: PI,
            theta_e,
        };
        if theta_o >= PI {
            return full;
        }
        let w = a.axis.cross(b.axis);
        let len = w.length();
        if len < 1e-6 {
            // Axes (anti)parallel but not nested: only the antiparallel case reaches here.
            return full;
        }
        let rot = Quat::from_axis_angle(w / len, theta_o - UNION_SLACK - a.theta_o);
        Cone {
            axis: (rot * a.axis).normalize(),
            theta_o,
            theta_e,
        }
    }

    /// Orientation measure M_Ω = 2π(1−cos θo) + π/2·[2θw sin θo − cos(θo−2θw) − 2θo sin θo + cos θo],
    /// θw = min(θo+θe, π): the SAOH's weight for how spread out the emission directions are,
    /// in [0, 4π] (4π for the full sphere).
    pub fn measure(&self) -> f32 {
        if self.theta_o >= PI {
            return 4.0 * PI;
        }
        let theta_o = self.theta_o.max(0.0);
        if theta_o == 0.0 {
            // π/2·(1 − cos 2θw) = π sin²θw
            let s = self.theta_e.min(PI).sin();
            return PI * s * s;
        }
        let theta_w = (theta_o + self.theta_e).min(PI);
        let (so, co) = theta_o.sin_cos();
        2.0 * PI * (1.0 - co)
            + FRAC_PI_2
                * (2.0 * theta_w * so - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * so + co)
    }
}

/// Angle between two unit vectors, accurate near 0 and π.
#[inline]
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((a - b).length() * 0.5).min(1.0).asin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn rand_dir(rng: &mut impl rand::Rng) -> Vec3 {
        let z = 1.0 - 2.0 * rng.random::<f32>();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * rng.random::<f32>();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    #[test]
    fn measure_known_values() {
        let lamb = Cone {
            axis: Vec3::Z,
            theta_o: 0.0,
            theta_e: FRAC_PI_2,
        };
        assert!((lamb.measure() - PI).abs() < 1e-5);
        let sphere = Cone {
            axis: Vec3::Z,
            theta_o: PI,
            theta_e: FRAC_PI_2,
        };
        assert!((sphere.measure() - 4.0 * PI).abs() < 1e-4);
        // The fast paths agree with the general formula just inside them.
        for theta_e in [0.0, 0.3, FRAC_PI_2, 2.5, PI] {
            for (fast, near) in [(0.0, 1e-4), (PI, PI - 1e-4)] {
                let m = |theta_o| {
                    Cone {
                        axis: Vec3::Z,
                        theta_o,
                        theta_e,
                    }
                    .measure()
                };
                assert!((m(fast) - m(near)).abs() < 2e-3, "{theta_e} {fast}");
            }
        }
    }

    #[test]
    fn union_identity_and_containment() {
        let c = Cone {
            axis: Vec3::new(0.0, 0.6, 0.8),
            theta_o: 0.3,
            theta_e: 1.0,
        };
        assert_eq!(Cone::union(Cone::EMPTY, c), c);
        assert_eq!(Cone::union(c, Cone::EMPTY), c);
        let opp = Cone {
            axis: -c.axis,
            theta_o: 0.0,
            theta_e: 0.5,
        };
        assert_eq!(Cone::union(c, opp).theta_o, PI);
    }

    /// Random cones: every direction inside either input cone is inside the union.
    #[test]
    fn union_is_conservative() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        for _ in 0..2000 {
            let a = Cone {
                axis: rand_dir(&mut rng),
                theta_o: rng.random::<f32>() * 1.5,
                theta_e: rng.random::<f32>(),
            };
            let b = Cone {
                axis: rand_dir(&mut rng),
                theta_o: rng.random::<f32>() * 1.5,
                theta_e: rng.random::<f32>(),
            };
            let u = Cone::union(a, b);
            assert!(u.theta_e >= a.theta_e.max(b.theta_e));
            for c in [a, b] {
                // The farthest direction of c from u's axis must be within u.theta_o.
                let far = angle_between(u.axis, c.axis) + c.theta_o;
                assert!(
                    far.min(PI) <= u.theta_o + 1e-4,
                    "a={a:?} b={b:?} u={u:?} far={far}"
                );
            }
        }
    }
}
