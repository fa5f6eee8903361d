//! The motion of the bodies: [`flight`] (exact torque-free free flight), [`aim`] (the
//! launch that reaches a pose at `t`), [`contact`]
//! (first contact times, between bodies and with the table), [`continuation`] (rapier3d
//! after `t` and after contacts, for the animated export), [`drag`] (quadratic air
//! drag) and [`launch_error`] (the launcher's errors).

pub mod aim;
pub mod contact;
pub mod continuation;
pub mod drag;
pub mod flight;
pub mod launch_error;
