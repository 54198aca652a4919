//! What happens at the boundary of the material: the walls of the grid's faces and the
//! periodic faces ([`walls`], E20, E95), and the colliders' solids, poses and contact law
//! ([`colliders`], E90-E93). The grid update applies them in one place, on the updated
//! velocity, in this order: the nodal damping, the colliders, then the walls
//! ([`crate::phases::grid_update`]); a particle that reaches a wall plane is put back on it in
//! the particle update ([`crate::phases::update`]), one carried into a solid is put back out
//! after the substep (`World::put_out_of_colliders`).

pub(crate) mod colliders;
mod walls;
