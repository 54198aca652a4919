//! The terms the declared effects ([`crate::Effects`]) add to a step. An effect that is not
//! declared reserves no column and runs no loop.
//! - [`damping`]: the damping acceleration of the particle update, the nodal damping of the
//!   grid update, the per-particle rates of a chunk (E48-E53).
//! - [`forces`]: the tractions' pass (E14-E16).
//!
//! Heat conduction and diffusion (E54-E64) are a pass of their own,
//! [`crate::phases::transport`]. The declarations are in [`crate::def`], the setters of the
//! effects' per-particle data on [`crate::World`].

pub(crate) mod damping;
pub(crate) mod forces;
