//! The launch values of one occluder, and their place in the optimizer's flat vector.
//!
//! CMA-ES searches a flat `Vec<f64>` with six values per occluder; everywhere else reads
//! and writes it through [`Launch`], so the layout is written down once, here.

use glam::DVec3;

/// What the optimizer searches for one occluder: its launch velocities.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Launch {
    /// Centre-of-mass launch velocity (m/s, world).
    pub velocity: DVec3,
    /// Launch angular velocity (rad/s, world).
    pub angular_velocity: DVec3,
}

impl Launch {
    /// Values per occluder in a parameter vector: `[v.x, v.y, v.z, w.x, w.y, w.z]`.
    pub const LEN: usize = 6;

    /// The launch of occluder `i` in the parameter vector `params`.
    pub fn get(params: &[f64], i: usize) -> Launch {
        let p = &params[Self::LEN * i..Self::LEN * (i + 1)];
        Launch {
            velocity: DVec3::new(p[0], p[1], p[2]),
            angular_velocity: DVec3::new(p[3], p[4], p[5]),
        }
    }

    /// Store this launch as occluder `i`'s in `params`.
    pub fn set(self, params: &mut [f64], i: usize) {
        params[Self::LEN * i..Self::LEN * (i + 1)].copy_from_slice(&self.to_array());
    }

    /// The six values in parameter order.
    pub fn to_array(self) -> [f64; 6] {
        let (v, w) = (self.velocity, self.angular_velocity);
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// Copy occluder `from`'s values in `src` into the slot of occluder `to` in `dst`.
    pub fn copy(src: &[f64], from: usize, dst: &mut [f64], to: usize) {
        dst[Self::LEN * to..Self::LEN * (to + 1)]
            .copy_from_slice(&src[Self::LEN * from..Self::LEN * (from + 1)]);
    }
}

/// The launch velocity that puts a centre of mass launched at `from` at `to` after `t`
/// seconds of flight in a vacuum under `gravity`: `from + v t + gravity t^2 / 2 = to`.
pub fn velocity_reaching(from: DVec3, to: DVec3, gravity: DVec3, t: f64) -> DVec3 {
    (to - from - 0.5 * gravity * t * t) / t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_set_and_copy_keep_the_six_values_in_order() {
        let mut p: Vec<f64> = (0..18).map(f64::from).collect();
        let l = Launch::get(&p, 1);
        assert_eq!(l.velocity, DVec3::new(6.0, 7.0, 8.0));
        assert_eq!(l.angular_velocity, DVec3::new(9.0, 10.0, 11.0));
        assert_eq!(l.to_array(), [6.0, 7.0, 8.0, 9.0, 10.0, 11.0]);
        l.set(&mut p, 2);
        assert_eq!(&p[12..], &[6.0, 7.0, 8.0, 9.0, 10.0, 11.0]);
        let mut q = vec![0.0; 6];
        Launch::copy(&p, 0, &mut q, 0);
        assert_eq!(q, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    }
}
