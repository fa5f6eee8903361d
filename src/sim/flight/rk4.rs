//! The RK4 step of an asymmetric body's orientation, written once over a [`Lane`]: `f64`
//! for one flight, [`Wide`] for [`LANES`] flights side by side.
//!
//! Every operation is applied lane by lane in the same order as for one flight, and a
//! product or sum of two `f64` lanes is the IEEE result of those two numbers alone, so a
//! flight integrated in a lane of [`Wide`] gets the same bits as alone. The wide form is
//! there because one grid is a serial chain of dependent products that leaves most of
//! the core idle; four chains fill the vector units (two lanes per SSE2 instruction).

use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::{DQuat, DVec3};

/// Flights one [`Wide`] value carries.
pub const LANES: usize = 4;

/// A number, or [`LANES`] of them operated on lane by lane.
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// `v` in every lane.
    fn splat(v: f64) -> Self;
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(v: f64) -> f64 {
        v
    }
}

/// [`LANES`] numbers, one per flight, in one SSE2 register (every x86-64 CPU has SSE2).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Wide(std::arch::x86_64::__m128d, std::arch::x86_64::__m128d);

#[cfg(target_arch = "x86_64")]
mod wide {
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Neg, Sub};

    use super::{Lane, Wide, LANES};

    macro_rules! lanewise {
        ($trait:ident, $f:ident, $op:ident) => {
            impl $trait for Wide {
                type Output = Wide;
                #[inline(always)]
                fn $f(self, b: Wide) -> Wide {
                    // SAFETY: SSE2 is part of x86-64, so every x86-64 CPU has it.
                    unsafe { Wide($op(self.0, b.0), $op(self.1, b.1)) }
                }
            }
        };
    }
    lanewise!(Add, add, _mm_add_pd);
    lanewise!(Sub, sub, _mm_sub_pd);
    lanewise!(Mul, mul, _mm_mul_pd);
    lanewise!(Div, div, _mm_div_pd);

    impl Neg for Wide {
        type Output = Wide;
        /// The sign bit flipped, as `-x` does to an `f64`.
        #[inline(always)]
        fn neg(self) -> Wide {
            // SAFETY: SSE2 is part of x86-64.
            unsafe {
                Wide(
                    _mm_xor_pd(self.0, _mm_set1_pd(-0.0)),
                    _mm_xor_pd(self.1, _mm_set1_pd(-0.0)),
                )
            }
        }
    }

    impl Lane for Wide {
        #[inline(always)]
        fn splat(v: f64) -> Wide {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Wide(_mm_set1_pd(v), _mm_set1_pd(v)) }
        }
    }

    impl Wide {
        /// The lanes as numbers.
        #[inline(always)]
        pub fn lanes(self) -> [f64; LANES] {
            // SAFETY: SSE2 is part of x86-64.
            unsafe {
                [
                    _mm_cvtsd_f64(self.0),
                    _mm_cvtsd_f64(_mm_unpackhi_pd(self.0, self.0)),
                    _mm_cvtsd_f64(self.1),
                    _mm_cvtsd_f64(_mm_unpackhi_pd(self.1, self.1)),
                ]
            }
        }

        /// Numbers as lanes.
        #[inline(always)]
        pub fn from_lanes(v: [f64; LANES]) -> Wide {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Wide(_mm_set_pd(v[1], v[0]), _mm_set_pd(v[3], v[2])) }
        }
    }
}

/// [`LANES`] numbers, one per flight (on other targets than x86-64, as an array).
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Copy, Debug)]
pub struct Wide([f64; LANES]);

#[cfg(not(target_arch = "x86_64"))]
mod wide {
    use std::ops::{Add, Div, Mul, Neg, Sub};

    use super::{Lane, Wide, LANES};

    macro_rules! lanewise {
        ($trait:ident, $f:ident, $op:tt) => {
            impl $trait for Wide {
                type Output = Wide;
                #[inline(always)]
                fn $f(self, b: Wide) -> Wide {
                    Wide(std::array::from_fn(|i| self.0[i] $op b.0[i]))
                }
            }
        };
    }
    lanewise!(Add, add, +);
    lanewise!(Sub, sub, -);
    lanewise!(Mul, mul, *);
    lanewise!(Div, div, /);

    impl Neg for Wide {
        type Output = Wide;
        #[inline(always)]
        fn neg(self) -> Wide {
            Wide(self.0.map(|x| -x))
        }
    }

    impl Lane for Wide {
        #[inline(always)]
        fn splat(v: f64) -> Wide {
            Wide([v; LANES])
        }
    }

    impl Wide {
        /// The lanes as numbers.
        #[inline(always)]
        pub fn lanes(self) -> [f64; LANES] {
            self.0
        }

        /// Numbers as lanes.
        #[inline(always)]
        pub fn from_lanes(v: [f64; LANES]) -> Wide {
            Wide(v)
        }
    }
}

/// A quaternion `(x, y, z, w)` over a [`Lane`].
#[derive(Clone, Copy, Debug)]
pub struct Quat<T>(pub [T; 4]);

/// A vector `(x, y, z)` over a [`Lane`].
pub type Vec3<T> = [T; 3];

impl<T: Lane> Quat<T> {
    #[inline(always)]
    fn plus(self, b: Quat<T>) -> Quat<T> {
        Quat(std::array::from_fn(|i| self.0[i] + b.0[i]))
    }

    #[inline(always)]
    fn times(self, s: T) -> Quat<T> {
        Quat(self.0.map(|c| c * s))
    }
}

/// Time derivative of the principal-to-world quaternion: `q' = q (0, w_p) / 2` with the
/// principal-frame angular velocity `w_p = I^-1 (q^* L q)`. Both products are polynomial
/// in `q`, so the field is smooth off the unit sphere and RK4 keeps its fourth order even
/// though the stage values are not normalised.
#[inline(always)]
fn quat_rate<T: Lane>(q: Quat<T>, l: Vec3<T>, half_inv_inertia: Vec3<T>) -> Quat<T> {
    // Written out in scalars: the RK4 stages form one long dependency chain, and this
    // form has a shorter critical path than composing glam's generic products.
    let [x, y, z, w] = q.0;
    let [lx, ly, lz] = l;
    let two = T::splat(2.0);
    // v = q^* L q = (w^2 - b^2) L + 2 (b . L) b - 2 w (b x L), with b = (x, y, z).
    let s = w * w - (x * x + y * y + z * z);
    let d = two * (x * lx + y * ly + z * lz);
    let w2 = two * w;
    let vx = s * lx + d * x - w2 * (y * lz - z * ly);
    let vy = s * ly + d * y - w2 * (z * lx - x * lz);
    let vz = s * lz + d * z - w2 * (x * ly - y * lx);
    // Half the principal angular velocity, then q (0, w_p / 2).
    let [hx, hy, hz] = half_inv_inertia;
    let (ax, ay, az) = (vx * hx, vy * hy, vz * hz);
    Quat([
        w * ax + y * az - z * ay,
        w * ay + z * ax - x * az,
        w * az + x * ay - y * ax,
        -(x * ax + y * ay + z * az),
    ])
}

/// One classical RK4 step of length `h` for [`quat_rate`] (result not normalised).
#[inline(always)]
pub fn rk4_step<T: Lane>(q: Quat<T>, h: T, l: Vec3<T>, half_inv_inertia: Vec3<T>) -> Quat<T> {
    let half_h = T::splat(0.5) * h;
    let k1 = quat_rate(q, l, half_inv_inertia);
    let k2 = quat_rate(q.plus(k1.times(half_h)), l, half_inv_inertia);
    let k3 = quat_rate(q.plus(k2.times(half_h)), l, half_inv_inertia);
    let k4 = quat_rate(q.plus(k3.times(h)), l, half_inv_inertia);
    let sum = k1.plus(k2.plus(k3).times(T::splat(2.0))).plus(k4);
    q.plus(sum.times(h / T::splat(6.0)))
}

/// Pulls a nearly unit quaternion back to unit length with one Newton step for
/// `1 / sqrt(|q|^2)`: RK4 changes the norm by far less than 1e-9 per step, so the
/// residual (~ the square of that) is below rounding, and the step avoids the square
/// root and division that would lengthen the serial chain of the integration.
#[inline(always)]
pub fn renormalize<T: Lane>(q: Quat<T>) -> Quat<T> {
    let [x, y, z, w] = q.0;
    let norm2 = x * x + y * y + z * z + w * w;
    q.times(T::splat(1.5) - T::splat(0.5) * norm2)
}

impl From<DQuat> for Quat<f64> {
    #[inline(always)]
    fn from(q: DQuat) -> Quat<f64> {
        Quat(q.to_array())
    }
}

impl From<Quat<f64>> for DQuat {
    #[inline(always)]
    fn from(q: Quat<f64>) -> DQuat {
        DQuat::from_array(q.0)
    }
}

/// `v` as a [`Vec3`] of `f64`.
#[inline(always)]
pub fn vec3(v: DVec3) -> Vec3<f64> {
    v.to_array()
}

/// One flight's [`rk4_step`] on glam's types.
#[inline(always)]
pub fn rk4_step_one(q: DQuat, h: f64, l: DVec3, half_inv_inertia: DVec3) -> DQuat {
    rk4_step(Quat::from(q), h, vec3(l), vec3(half_inv_inertia)).into()
}

/// One flight's [`renormalize`] on glam's types.
#[inline(always)]
pub fn renormalize_one(q: DQuat) -> DQuat {
    renormalize(Quat::from(q)).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_four_abreast_gives_the_bits_of_each_alone() {
        let quats = [
            DQuat::from_xyzw(0.1, -0.7, 0.3, 0.6).normalize(),
            DQuat::from_xyzw(-0.5, 0.2, 0.8, -0.1).normalize(),
            DQuat::IDENTITY,
            DQuat::from_xyzw(0.9, 0.1, -0.2, 0.3).normalize(),
        ];
        let ls = [
            DVec3::new(0.3, -1.2, 2.5),
            DVec3::new(-4.0, 0.01, 0.7),
            DVec3::ZERO,
            DVec3::new(1e-3, 7.0, -0.2),
        ];
        let his = [
            DVec3::new(40.0, 3.1, 2.9),
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::splat(0.5),
            DVec3::new(150.0, 12.5, 11.0),
        ];
        let hs = [0.01, 0.0031, 0.05, 1e-4];
        let wide = |f: &dyn Fn(usize) -> f64| Wide::from_lanes(std::array::from_fn(f));
        let q = Quat(std::array::from_fn(|c| wide(&|j| quats[j].to_array()[c])));
        let l = std::array::from_fn(|c| wide(&|j| ls[j].to_array()[c]));
        let hi = std::array::from_fn(|c| wide(&|j| his[j].to_array()[c]));
        let stepped = renormalize(rk4_step(q, wide(&|j| hs[j]), l, hi));
        for j in 0..LANES {
            let alone = renormalize_one(rk4_step_one(quats[j], hs[j], ls[j], his[j]));
            let lane: [f64; 4] = std::array::from_fn(|c| stepped.0[c].lanes()[j]);
            assert_eq!(
                alone.to_array().map(f64::to_bits),
                lane.map(f64::to_bits),
                "lane {j}"
            );
        }
    }
}
