//! Designing scenes from a box of objects: [`inventory`] (the object list a user writes)
//! and [`plant`] (problems with a known answer: a random contact-free launch whose
//! shadow becomes the target).

pub mod cover;
pub mod inventory;
pub mod plant;
