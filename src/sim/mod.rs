//! The motion of the bodies: [`flight`] (exact torque-free free flight), [`contact`]
//! (first contact times, between bodies and with the table), [`continuation`] (rapier3d
//! after `t` and after contacts, for the animated export) and [`drag`] (quadratic air
//! drag, for the error budget).

pub mod contact;
pub mod continuation;
pub mod drag;
pub mod flight;
