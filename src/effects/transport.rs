//! Heat conduction and diffusion (E54-E64): the declaration of a
//! transported scalar and its boundary conditions, and the setters of its per-particle values
//! and sources. The pass that moves the scalars through the grid is
//! [`crate::phases::transport`].

use crate::layout::Layout;
use crate::world::{ScalarField, World};
use crate::{Error, Real};

/// Boundary condition of a transported scalar (temperature or concentration potential) on one
/// face of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScalarBoundary {
    /// No flow across the face (the natural condition of E55).
    Insulated,
    /// The value held fixed on the face: the nodes from the grid face to the wall plane (as the
    /// walls of [`crate::Boundary`]) take it.
    Fixed(Real),
    /// A flow into the domain per unit area of the face (W/m^2 for heat, m/s for the
    /// concentration potential), applied on the wall plane's nodes (E60).
    Flux(Real),
}

/// A transported scalar field (heat conduction or diffusion, E54-E64):
/// its boundary conditions and whether particles carry a source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transport {
    /// Condition of each face, indexed by [`crate::Face`].
    pub faces: [ScalarBoundary; 6],
    /// Reserve a per-particle source column (W/m^3 for heat, 1/s for the concentration
    /// potential), set with [`crate::World::set_particle_sources`].
    pub sources: bool,
}

impl Transport {
    /// Every face insulated, no sources.
    pub const INSULATED: Transport = Transport {
        faces: [ScalarBoundary::Insulated; 6],
        sources: false,
    };

    /// Whether the faces of the `axes` used have finite values (the z faces of a 2D world are
    /// not read, like every other z component there).
    pub(crate) fn is_valid(&self, axes: usize) -> bool {
        self.faces[..2 * axes].iter().all(|f| match f {
            ScalarBoundary::Insulated => true,
            ScalarBoundary::Fixed(v) | ScalarBoundary::Flux(v) => v.is_finite(),
        })
    }
}

impl World<'_> {
    /// Sets the value of a transported scalar (temperature, K, or concentration potential) of
    /// particles `first..first + n`, `n = values.len()`. Needs the field declared
    /// ([`crate::Effects::heat`], [`crate::Effects::diffusion`]). Values start at 0.
    pub fn set_particle_scalar(
        &mut self,
        field: ScalarField,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        self.set_scalar_column(field, 0, first, values)
    }
    /// Sets the source of a transported scalar (heat: W/m^3; diffusion: 1/s) of particles
    /// `first..first + n`. Needs the field declared with [`crate::Transport::sources`].
    pub fn set_particle_sources(
        &mut self,
        field: ScalarField,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        self.set_scalar_column(field, 2, first, values)
    }
    fn set_scalar_column(
        &mut self,
        field: ScalarField,
        k: usize,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let g = layout.scalar[field as usize];
        let group = (k < g.count).then_some(g.first + k);
        self.write_particle_columns(
            &layout,
            group,
            first,
            &[values],
            Error::NonFiniteInput,
            |_| Ok(()),
        )
    }
}
