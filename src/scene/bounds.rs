//! The number checks of scene validation: every number finite, and bounded by the
//! limits of `super` (`MAX_COORDINATE`, `MAX_SPEED`, ...) so that the products the
//! physics forms cannot overflow and everything downstream may trust the scene.
//!
//! They are methods of [`Validator`], which this module takes from `super::validate`;
//! nothing is taken back: the wording of numbers in their messages, [`short`], is
//! `super`'s, shared with validation and the rest of the crate.

use glam::DVec3;

use super::validate::Validator;
use super::{short, Result, MAX_COORDINATE, MAX_T, MAX_WEIGHT, MIN_T};

impl Validator<'_> {
    pub(super) fn finite(&self, field: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must be a finite number, got {x}")))
        }
    }

    /// A finite number of magnitude at most `limit`: the bounds of `super::MAX_*` that
    /// keep every product of the physics finite.
    pub(super) fn within(&self, field: &str, x: f64, limit: f64) -> Result<f64> {
        let x = self.finite(field, x)?;
        if x.abs() <= limit {
            Ok(x)
        } else {
            Err(self.field_err(
                field,
                format!(
                    "must be between -{} and {}, got {}",
                    short(limit),
                    short(limit),
                    short(x)
                ),
            ))
        }
    }

    /// A positive number of at most `limit`.
    pub(super) fn positive_within(&self, field: &str, x: f64, limit: f64) -> Result<f64> {
        let x = self.positive(field, x)?;
        if x <= limit {
            Ok(x)
        } else {
            Err(self.field_err(
                field,
                format!("must be at most {}, got {}", short(limit), short(x)),
            ))
        }
    }

    /// A weight: from 0 to [`MAX_WEIGHT`].
    pub(super) fn weight(&self, field: &str, x: f64) -> Result<f64> {
        let x = self.non_negative(field, x)?;
        if x <= MAX_WEIGHT {
            Ok(x)
        } else {
            Err(self.field_err(
                field,
                format!("must be from 0 to {}, got {}", short(MAX_WEIGHT), short(x)),
            ))
        }
    }

    /// A picture's instant (s): from [`MIN_T`] to [`MAX_T`].
    pub(super) fn instant(&self, field: &str, t: f64) -> Result<f64> {
        let t = self.positive_within(field, t, MAX_T)?;
        if t < MIN_T {
            return Err(self.field_err(
                field,
                format!("must be at least {MIN_T} s, got {} s", short(t)),
            ));
        }
        Ok(t)
    }

    pub(super) fn positive(&self, field: &str, x: f64) -> Result<f64> {
        let x = self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must be positive, got {}", short(x))))
        }
    }

    pub(super) fn non_negative(&self, field: &str, x: f64) -> Result<f64> {
        let x = self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must not be negative, got {}", short(x))))
        }
    }

    /// A point or length vector: every component within [`MAX_COORDINATE`] metres.
    pub(super) fn vec3(&self, field: &str, a: [f64; 3]) -> Result<DVec3> {
        for (i, x) in a.iter().enumerate() {
            self.within(&format!("{field}[{i}]"), *x, MAX_COORDINATE)?;
        }
        Ok(DVec3::from_array(a))
    }

    /// A vector whose length is at most `limit` (speeds, gravity).
    pub(super) fn vec3_len_within(&self, field: &str, a: [f64; 3], limit: f64) -> Result<DVec3> {
        let v = self.vec3(field, a)?;
        let len = v.length();
        if len <= limit {
            Ok(v)
        } else {
            Err(self.field_err(
                field,
                format!("has magnitude {len:e}, more than the {limit:e} allowed"),
            ))
        }
    }

    pub(super) fn unit(&self, field: &str, a: [f64; 3]) -> Result<DVec3> {
        let v = self.vec3(field, a)?;
        let len = v.length();
        if len < 1e-12 {
            return Err(self.field_err(field, "must be a non-zero vector"));
        }
        Ok(v / len)
    }
}
