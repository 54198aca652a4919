//! The terms the declared effects ([`crate::Effects`]) add to a step. An effect that is not
//! declared reserves no column and runs no loop. Colliders are the boundary's
//! ([`crate::boundary`]).
//! - [`damping`]: the damping acceleration of the particle update, the nodal damping of the
//!   grid update, the per-particle rates of a chunk (E48-E53).
//!
//! Tractions (E15-E16) and heat conduction and diffusion (E54-E64) are passes of their own,
//! [`crate::phases::tractions`] and [`crate::phases::transport`]. The declarations are in [`crate::def`], the setters of the
//! effects' per-particle data on [`crate::World`].

pub(crate) mod damping;
