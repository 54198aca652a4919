//! The error type of every fallible call. Each variant has a stable number (the future C
//! `MpmStatus` uses the same values) and a static message.

use core::fmt;

/// Why a call failed. A call that returns an error has changed nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Error {
    /// The buffer is smaller than [`crate::memory_requirements`] says.
    BufferTooSmall = 1,
    /// The buffer does not start at the alignment [`crate::memory_requirements`] says.
    BufferMisaligned = 2,
    /// The buffer does not hold a world of this build (wrong magic, version, precision or size).
    NotAWorld = 3,
    /// The dimension is not supported by this build.
    Unsupported = 4,
    /// Cell size not finite or <= 0.
    InvalidCellSize = 5,
    /// Too few cells on an axis for the shape function's margin, or too many nodes to index.
    InvalidCellCount = 6,
    /// Particle or material capacity is zero or too large to index.
    InvalidCapacity = 7,
    /// FLIP fraction outside [0, 1].
    InvalidFlipBeta = 8,
    /// Courant number outside (0, 1].
    InvalidCfl = 9,
    /// Series terms for `exp(grad v dt)` outside 1..=8.
    InvalidExpTerms = 10,
    /// Particles per cell outside 1..=8.
    InvalidParticlesPerCell = 11,
    /// Origin or gravity not finite (on the axes the dimension uses).
    NonFiniteDefinition = 12,
    /// Young's modulus <= 0, Poisson's ratio outside (-1, 0.5), density <= 0, or not finite.
    InvalidMaterial = 13,
    /// The material table is full.
    MaterialCapacityExceeded = 14,
    /// The particles do not fit in the remaining capacity (none was added).
    ParticleCapacityExceeded = 15,
    /// A material id that names no material.
    UnknownMaterial = 16,
    /// A position, velocity, mass or volume that is NaN or infinite.
    NonFiniteInput = 17,
    /// A mass or volume <= 0.
    NonPositiveMassOrVolume = 18,
    /// A position outside the grid or inside the boundary margin the shape function needs.
    PositionOutsideDomain = 19,
    /// Input arrays of different lengths.
    LengthMismatch = 20,
    /// A time step that is <= 0 or not finite.
    InvalidTimeStep = 21,
    /// A region (box, disk, sphere) that is empty, inverted or not finite.
    InvalidRegion = 22,
}

impl Error {
    /// A static, human-readable description.
    pub const fn as_str(self) -> &'static str {
        match self {
            Error::BufferTooSmall => "buffer smaller than the memory requirement",
            Error::BufferMisaligned => "buffer not aligned as the memory requirement says",
            Error::NotAWorld => "buffer does not hold a world of this build",
            Error::Unsupported => "dimension not supported by this build",
            Error::InvalidCellSize => "cell size must be finite and > 0",
            Error::InvalidCellCount => "too few cells for the shape margin, or too many nodes",
            Error::InvalidCapacity => "capacity must be > 0 and small enough to index",
            Error::InvalidFlipBeta => "FLIP fraction beta must be in [0, 1]",
            Error::InvalidCfl => "Courant number must be in (0, 1]",
            Error::InvalidExpTerms => "exp(grad v dt) series terms must be in 1..=8",
            Error::InvalidParticlesPerCell => "particles per cell must be in 1..=8",
            Error::NonFiniteDefinition => "origin and gravity must be finite",
            Error::InvalidMaterial => {
                "material needs E > 0, -1 < nu < 0.5, density > 0, all finite"
            }
            Error::MaterialCapacityExceeded => "material table is full",
            Error::ParticleCapacityExceeded => "particles do not fit in the remaining capacity",
            Error::UnknownMaterial => "material id names no material",
            Error::NonFiniteInput => "position, velocity, mass or volume not finite",
            Error::NonPositiveMassOrVolume => "mass and volume must be > 0",
            Error::PositionOutsideDomain => {
                "position outside the grid or inside its boundary margin"
            }
            Error::LengthMismatch => "input arrays differ in length",
            Error::InvalidTimeStep => "time step must be finite and > 0",
            Error::InvalidRegion => "region is empty, inverted or not finite",
        }
    }

    /// Every variant, in numeric order (for tests and the C status table).
    pub const ALL: [Error; 22] = [
        Error::BufferTooSmall,
        Error::BufferMisaligned,
        Error::NotAWorld,
        Error::Unsupported,
        Error::InvalidCellSize,
        Error::InvalidCellCount,
        Error::InvalidCapacity,
        Error::InvalidFlipBeta,
        Error::InvalidCfl,
        Error::InvalidExpTerms,
        Error::InvalidParticlesPerCell,
        Error::NonFiniteDefinition,
        Error::InvalidMaterial,
        Error::MaterialCapacityExceeded,
        Error::ParticleCapacityExceeded,
        Error::UnknownMaterial,
        Error::NonFiniteInput,
        Error::NonPositiveMassOrVolume,
        Error::PositionOutsideDomain,
        Error::LengthMismatch,
        Error::InvalidTimeStep,
        Error::InvalidRegion,
    ];
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(feature = "std")]
extern crate std;

#[cfg(feature = "std")]
impl std::error::Error for Error {}
