//! World and material definitions: plain structs with documented defaults, and the enums that
//! choose the method (dimension, shape function, stress-update order, boundary conditions).
//!
//! Every field documents its unit and why its default is what it is. Units are SI throughout
//! (m, kg, s, Pa); any consistent unit system works because the kernel has no built-in constant
//! other than the default gravity.

pub(crate) mod effects;

use crate::{Real, Vec3};
pub use effects::{
    ColliderDef, ColliderShape, Contact, Damping, DampingZone, Effects, Feedback, ScalarBoundary,
    ScalarField, Schedule, Transport, DAMPING_ZONES, SCHEDULE_POINTS, TRACTION_SCHEDULES,
};

/// Spatial dimension and kinematic assumption of a world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Dimension {
    /// Two dimensions, plane strain: quantities are per unit thickness along z, and
    /// `F_zz = 1`, so the stress keeps a `tau_zz` component.
    Plane2D = 2,
    /// Two dimensions, axisymmetric (E65-E72): x is the radius r and y the axis z.
    /// Masses, volumes, forces and energies are per radian (a particle of cross-section `A_p`
    /// at radius `r_p` has volume `A_p r_p`), the weights are r-weighted, and the radial force
    /// has the hoop term. The axis `r = 0` must be the lower x face's wall plane:
    /// `origin.x = -margin_cells * cell_size` and that face a slip (or stick) wall, or
    /// [`crate::Error::InvalidAxis`]. The stored out-of-plane stress is `tau_thetatheta`, and
    /// [`crate::ParticlesView::hoop`] holds `F_thetatheta - 1`. Needs the `effects` feature.
    Axisymmetric2D = 4,
    /// Three dimensions.
    ThreeD = 3,
}

impl Dimension {
    /// The variant stored as `code` (its `repr(u32)` value), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour.
    pub const fn from_code(code: u32) -> Option<Dimension> {
        match code {
            2 => Some(Dimension::Plane2D),
            3 => Some(Dimension::ThreeD),
            4 => Some(Dimension::Axisymmetric2D),
            _ => None,
        }
    }
}

/// Grid shape function used for `S_ip` and `G_ip` (E4-E11).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum ShapeFunction {
    /// Classic MPM: linear hat functions, 2 nodes per axis. Cheapest; its gradient jumps when a
    /// particle crosses a cell edge (the cell-crossing error GIMP removes).
    Linear = 0,
    /// uGIMP (Bardenhagen and Kober 2004): linear hats integrated over an undeformed particle
    /// domain of half-width `l_p = h / (2 n)`, `n` = [`WorldDef::particles_per_cell`]. 3 nodes per axis.
    Gimp = 1,
    /// Quadratic B-spline, 3 nodes per axis.
    QuadraticBspline = 2,
    /// Cubic B-spline, 4 nodes per axis.
    CubicBspline = 3,
    /// cpGIMP (Wallstedt and Guilkey 2008): uGIMP whose particle domain is convected with the
    /// deformation. Along each axis the half-width is `l_p` times the extent of the deformed
    /// domain there, `sum_b |F_ab|` (`F_aa` under a stretch along the axes, as cpGIMP writes
    /// it; rotation-invariant in length), kept within `[l_p / 10, h / 2]` so that the domain
    /// stays within the 3 nodes per axis. Costs the deformation gradient's load in every pass.
    CpGimp = 4,
}

impl ShapeFunction {
    /// The variant stored as `code` (its `repr(u32)` value), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour.
    pub const fn from_code(code: u32) -> Option<ShapeFunction> {
        match code {
            0 => Some(ShapeFunction::Linear),
            1 => Some(ShapeFunction::Gimp),
            2 => Some(ShapeFunction::QuadraticBspline),
            3 => Some(ShapeFunction::CubicBspline),
            4 => Some(ShapeFunction::CpGimp),
            _ => None,
        }
    }
}

impl ShapeFunction {
    /// Twice the shift of the first node of a stencil: a particle at `s` cells from the grid
    /// origin has its first node at `floor(s + shift) - lead` (`shape::Shape1D::SHIFT`),
    /// `shift` being 0 or 1/2.
    pub(crate) const fn first_node_shift_halves(self) -> i64 {
        match self {
            ShapeFunction::Linear | ShapeFunction::CubicBspline => 0,
            _ => 1,
        }
    }

    /// The nodes of a particle's stencil along each axis (`shape::Shape1D`'s `K`).
    pub(crate) const fn stencil_width(self) -> usize {
        match self {
            ShapeFunction::Linear => 2,
            ShapeFunction::CubicBspline => 4,
            _ => 3,
        }
    }

    /// How far a grid function reaches from its node, in cells: 1 for the linear hats (which
    /// the GIMP families integrate), 1.5 and 2 for the quadratic and cubic B-splines. The
    /// colliders' contact band (E91).
    pub const fn grid_function_reach(self) -> f32 {
        match self {
            ShapeFunction::QuadraticBspline => 1.5,
            ShapeFunction::CubicBspline => 2.0,
            _ => 1.0,
        }
    }

    /// Width of the layer of cells, at each face of the grid, that particles may not enter:
    /// the nodes of a particle's stencil must exist. 0 for linear, 1 for the others.
    pub const fn margin_cells(self) -> u32 {
        match self {
            ShapeFunction::Linear => 0,
            _ => 1,
        }
    }
}

/// Where the stress update sits in a step (Bardenhagen 2002; NairnMPM's task order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum UpdateOrder {
    /// Update stress first: from the nodal velocities `p_i / m_i` before the momentum update.
    Usf = 0,
    /// Update stress last: from the updated nodal velocities, in the same pass as the particle
    /// update. One particle-to-grid and one grid-to-particle pass: the cheapest.
    ///
    /// Do not combine with [`ShapeFunction::Linear`] in scenes where particles cross cells:
    /// a node that carries only a sliver of a particle's mass gets an unbounded acceleration
    /// `f_i / m_i` while the linear gradient stays finite, and the velocity gradient blows up
    /// (Bardenhagen 2002). The step contains it (affected particles are frozen and reported),
    /// but the scene is lost. USF or MUSL, or any smoother shape function, avoid it.
    Usl = 1,
    /// Modified USL: after the particle update, map the new particle momenta back to the grid
    /// and take the velocity gradient from them. Most robust where nodal masses are tiny.
    Musl = 2,
}

impl UpdateOrder {
    /// The variant stored as `code` (its `repr(u32)` value), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour.
    pub const fn from_code(code: u32) -> Option<UpdateOrder> {
        match code {
            0 => Some(UpdateOrder::Usf),
            1 => Some(UpdateOrder::Usl),
            2 => Some(UpdateOrder::Musl),
            _ => None,
        }
    }
}

/// How velocity moves from the grid back to the particles. Stored and passed to C as its
/// [`Transfer::code`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Transfer {
    /// FLIP blended with PIC by [`WorldDef::flip_beta`] (E22-E26). The
    /// particle moves by the grid's velocity and acceleration at its place, `x_p += (v_gp +
    /// a_gp dt / 2) dt` less the PIC and damping terms (E26). The velocity update takes the
    /// acceleration at the start of the step, so the scheme is first order in time: on the
    /// vibrating bar its time error halves with the step.
    Flip = 0,
    /// APIC (E78-E80): the particle takes the grid velocity (PIC) plus an affine matrix
    /// `C_p = B_p D_p^-1`, with `B_p = sum_i S_ip v_i (x_i - x_p)^T` and
    /// `D_p = sum_i S_ip (x_i - x_p)(x_i - x_p)^T` evaluated per particle, so the transfer
    /// conserves angular momentum with every shape function (the shortcut
    /// `D_p = h^2/4` or `h^2/3` holds only for the quadratic and cubic B-splines). The particle
    /// moves with the grid velocity, `x_p += v_p(n+1) dt`, and `flip_beta` is not used.
    /// Reserves D x D columns for `C_p`.
    Apic = 1,
    /// FLIP blended with PIC as [`Transfer::Flip`], the particle moving with its own new
    /// velocity, `x_p += v_p(n+1) dt` (E27; symplectic Euler on the particles,
    /// as APIC moves them). On the vibrating bar its time error is a hundredth of
    /// [`Transfer::Flip`]'s, about APIC's. But with `flip_beta` near 1 the particles then
    /// follow the noise of the FLIP velocity, which E26's grid velocity filters out: on the
    /// accuracy report's manufactured large deformation it does not converge (errors of 0.26
    /// to 0.87 of the amplitude with the default blend, against 0.01 to 0.03 with
    /// [`Transfer::Flip`]; with cpGIMP and `flip_beta` 0.5 or 0 it is 0.013 to 0.027, as
    /// accurate as [`Transfer::Flip`]). For vibration and waves, not for large flows. Same
    /// columns and cost as [`Transfer::Flip`].
    FlipParticleVelocity = 2,
    /// MLS-MPM (E82-E84): APIC's transfer, and every gradient of the momentum equation the
    /// MLS gradient `D_p^-1 S_ip (x_i - x_p)` in place of the shape function's `G_ip`: the
    /// nodal force is `f_i = -sum_p D_p^-1 S_ip V0 P F^T (x_i - x_p)` (E83, `D_p^-1 = 4 / h^2`
    /// with the quadratic B-spline, `3 / h^2` with the cubic), and the velocity gradient that
    /// updates F is `C_p` itself (`dF = exp(C_p dt)`). It is not the gradient of `S_ip` (it
    /// equals it for an affine velocity field only), but the force is then the exact
    /// derivative of the energy with respect to the nodal motion that the same `C_p` gives.
    /// The quadratic and cubic B-splines only (where `D_p` is constant), in 2D and 3D; any
    /// other shape function, or the axisymmetric form, is [`crate::Error::InvalidTransfer`].
    /// Heat and diffusion keep the shape functions' gradients. Reserves the columns of `C_p`
    /// as [`Transfer::Apic`] does.
    Mls = 3,
    /// FLIP in Nairn's momentum approach (E73-E77): the particle reads the grid
    /// through the nodes' momenta over the grid's mass at the particle, `m_gp = sum_i S_ip
    /// m_i`, so a node that carries a sliver of mass weighs in with that sliver. The
    /// velocity gradient is that of the mass-weighted velocity field (E74; E73 where the mass is
    /// uniform, and invariant under translation and exact for rigid rotation everywhere), the
    /// internal force its work conjugate (E75; energy, momentum and angular momentum pass between
    /// particles and grid unchanged), and the particle moves with the mass-weighted grid
    /// velocity (E76). The particle velocity takes [`Transfer::Flip`]'s update (E77: read
    /// with the particle's share of each nodal force, which conserves momentum). Plane strain
    /// and 3D, every shape function; the axisymmetric form is
    /// [`crate::Error::InvalidTransfer`]. Same columns as [`Transfer::Flip`]; a step costs 1.4
    /// to 2 times the velocity approach's (benches/PERFORMANCE.md, "What an effect costs").
    /// See `phases/momentum.rs` for why E73 is not used.
    ///
    /// For dynamics, not for stresses at rest next to a free or loaded face: the conjugate
    /// force does not balance a uniform stress there particle by particle. A plane-strain
    /// block pulled by a traction settles to the load's mean stress (within 0.1 %), but with
    /// particles by its faces up to 28 % off (uGIMP; 0.2 % with [`Transfer::Flip`]).
    FlipMomentum = 4,
    /// XPIC(k) (Hammerquist and Nairn 2017; E98-E100), `k` in `1..=`[`MAX_TRANSFER_ORDER`]:
    /// the particle takes `v(n+1) = S (v* + a dt)`, with `v*` the series `sum_{r=1..k}
    /// (-1)^(r+1) C(k, r) A^(r-1) v^L` of the lumped nodal velocity `v^L` of the step's
    /// start, `A = S+ S` (a gather to the particles, then their mass-weighted projection back
    /// to the nodes), and moves by `x(n+1) = x_p + (S v^L + (v(n+1) - v_p) / 2) dt`. XPIC(1)
    /// is PIC; as `k` grows it keeps more of what FLIP keeps, without FLIP's noise (the null
    /// space of `S` is filtered out). `flip_beta` and `pic_rate` are not used. Costs `k - 1`
    /// extra gather and scatter passes of the velocity alone, on the calling thread (2D: 17.2
    /// ns per particle-step for XPIC(2), 27.8 for XPIC(5), against FLIP's 12.0;
    /// benches/PERFORMANCE.md), and `D` extra grid columns (`2 D` with USL) where `k >= 2`.
    Xpic(u32) = 5,
    /// FMPM(k) (Nairn and Hammerquist 2021; E101), `k` in `1..=`[`MAX_FMPM_ORDER`]: the same
    /// series applied to the updated lumped velocity `v^L+ = v^L + a dt`, an approximation of
    /// order `k` of the full mass matrix's inverse; the particle takes `v(n+1) = S v*` and
    /// moves by the mean of its velocities, `x(n+1) = x_p + (v_p + v(n+1)) dt / 2`. With MUSL
    /// the re-mapped velocities pass through the series too (`k - 1` more passes). FMPM(2)
    /// with USL, whose stress update reads `v*`, is [`crate::Error::InvalidTransfer`]: on the
    /// vibrating bar its energy grew 18-fold in 5 periods at the default Courant number.
    /// Otherwise the costs of [`Transfer::Xpic`].
    Fmpm(u32) = 6,
}

/// Highest order `k` of [`Transfer::Xpic`]: each order past 1 costs a gather and scatter pass,
/// and past 8 the series changes little (`C(k, r)` grows as `2^k`).
pub const MAX_TRANSFER_ORDER: u32 = 8;

/// Highest order `k` of [`Transfer::Fmpm`]: from FMPM(3) on, the vibrating bar's energy grows
/// without bound at every Courant number tried (0.2 to 0.5), here with the stress from the
/// re-mapped velocities through the series; FMPM(2) keeps it within 0.07 %.
pub const MAX_FMPM_ORDER: u32 = 2;

impl Transfer {
    /// Whether the transfer carries the affine matrix `C_p` (APIC and MLS-MPM).
    pub const fn is_affine(self) -> bool {
        matches!(self, Transfer::Apic | Transfer::Mls)
    }

    /// XPIC's or FMPM's order `k` and whether it is FMPM; `None` for the other transfers.
    pub const fn series(self) -> Option<(u32, bool)> {
        match self {
            Transfer::Xpic(k) => Some((k, false)),
            Transfer::Fmpm(k) => Some((k, true)),
            _ => None,
        }
    }

    /// The number that stores the transfer (the C `transfer` field): the variant's number
    /// (0 to 6) in the low 8 bits, XPIC's or FMPM's order above them, `5 + 256 k` for
    /// XPIC(k).
    pub const fn code(self) -> u32 {
        match self {
            Transfer::Flip => 0,
            Transfer::Apic => 1,
            Transfer::FlipParticleVelocity => 2,
            Transfer::Mls => 3,
            Transfer::FlipMomentum => 4,
            Transfer::Xpic(k) => 5 | k << 8,
            Transfer::Fmpm(k) => 6 | k << 8,
        }
    }

    /// The transfer stored as `code` ([`Transfer::code`]), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour. An order out of range is kept
    /// (the definition's validation refuses it).
    pub const fn from_code(code: u32) -> Option<Transfer> {
        let k = code >> 8;
        match (code & 0xff, k) {
            (0, 0) => Some(Transfer::Flip),
            (1, 0) => Some(Transfer::Apic),
            (2, 0) => Some(Transfer::FlipParticleVelocity),
            (3, 0) => Some(Transfer::Mls),
            (4, 0) => Some(Transfer::FlipMomentum),
            (5, _) => Some(Transfer::Xpic(k)),
            (6, _) => Some(Transfer::Fmpm(k)),
            _ => None,
        }
    }
}

/// Boundary condition of one face of the grid box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Boundary {
    /// Nodes at the wall have zero velocity; particles reaching the wall stop against it.
    /// Nodes past the wall plane (reached by the B-splines) mirror those inside with every
    /// velocity component flipped.
    Stick = 0,
    /// Nodes at the wall have zero normal velocity; particles slide along the wall. Nodes past
    /// the wall plane mirror those inside with the normal component flipped: the wall is a
    /// plane of symmetry.
    Slip = 1,
    /// No condition on the nodes; a particle that crosses this face leaves the simulation
    /// (status [`crate::ParticleStatus::Escaped`]) and is counted in the step report.
    Open = 2,
    /// The material that leaves through this face comes back through the opposite one, which
    /// must be periodic too (E95): the admissible region wraps along the axis, whose period
    /// is the admissible length `(cells - 2 margin) h`, and the nodes past its faces are the
    /// images of the nodes inside. Not on the radial axis of an axisymmetric world, nor with
    /// a wall's friction or velocity or a scalar condition other than insulated. Colliders,
    /// distance fields and damping zones do not wrap.
    Periodic = 3,
}

impl Boundary {
    /// The variant stored as `code` (its `repr(u32)` value), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour.
    pub const fn from_code(code: u32) -> Option<Boundary> {
        match code {
            0 => Some(Boundary::Stick),
            1 => Some(Boundary::Slip),
            2 => Some(Boundary::Open),
            3 => Some(Boundary::Periodic),
            _ => None,
        }
    }
}

/// Index of each face in [`WorldDef::faces`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Face {
    /// The face at the lowest x.
    XMin = 0,
    /// The face at the highest x.
    XMax = 1,
    /// The face at the lowest y.
    YMin = 2,
    /// The face at the highest y.
    YMax = 3,
    /// The face at the lowest z (3D only).
    ZMin = 4,
    /// The face at the highest z (3D only).
    ZMax = 5,
}

impl Face {
    /// The variant stored as `code` (its `repr(u32)` value), if any.
    pub const fn from_code(code: u32) -> Option<Face> {
        match code {
            0 => Some(Face::XMin),
            1 => Some(Face::XMax),
            2 => Some(Face::YMin),
            3 => Some(Face::YMax),
            4 => Some(Face::ZMin),
            5 => Some(Face::ZMax),
            _ => None,
        }
    }
}

/// Constitutive model of a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum MaterialModel {
    /// Isotropic linear elasticity, small strain, in the corotated frame: with `F = R U`,
    /// `sigma = R (lambda tr(e) I + 2 mu e) R^T` for `e = U - I`. Rotations create no stress.
    LinearElastic = 0,
    /// Compressible neo-Hookean: `tau = mu (B - I) + lambda ln(J) I`, `B = F F^T`.
    NeoHookean = 1,
    /// Fixed-corotated elasticity (Stomakhin et al. 2012), the usual solid of game MPM:
    /// `tau = 2 mu (F - R) F^T + lambda (J - 1) J I` with `F = R S`. Rotations create no
    /// stress; unlike [`MaterialModel::LinearElastic`] it stays well posed at large strain.
    FixedCorotated = 2,
    /// Weakly compressible fluid: pressure from the volume ratio only (Tait's equation,
    /// `p = K / gamma (J^-gamma - 1)`, [`MaterialDef::bulk_modulus`] and
    /// [`MaterialDef::pressure_exponent`]), no elastic shear stress, plus the Newtonian
    /// viscous stress of [`MaterialDef::viscosity`]. The deformation gradient is kept as
    /// `J^(1/3) I`, so only J is carried and no shear accumulates.
    Fluid = 3,
    /// Metal: J2 (von Mises) plasticity with linear isotropic hardening
    /// ([`MaterialDef::yield_stress`], [`MaterialDef::hardening_modulus`]), `F = F_e F_p`,
    /// Hencky elasticity on `F_e` and the radial return in principal logarithmic strains.
    /// Needs [`crate::Effects::plasticity`] (the equivalent plastic strain per particle).
    VonMises = 4,
    /// Sand: Drucker-Prager plasticity on Hencky elasticity with the return mapping of Klar et
    /// al. 2016 ([`MaterialDef::friction_angle`], [`MaterialDef::cohesion`]); no volume
    /// correction. Needs [`crate::Effects::plasticity`] (the accumulated plastic shear).
    DruckerPrager = 5,
    /// Snow: fixed-corotated elasticity of `F_e` whose singular values are clamped to
    /// `[1 - theta_c, 1 + theta_s]` and whose moduli harden as `exp(xi (1 - J_p))`
    /// (Stomakhin et al. 2013: [`MaterialDef::critical_compression`],
    /// [`MaterialDef::critical_stretch`], [`MaterialDef::hardening_coefficient`]). Needs
    /// [`crate::Effects::plasticity`] (`J_p - 1` per particle).
    Snow = 6,
}

impl MaterialModel {
    /// Every model, in the order of their numbers.
    pub const ALL: [MaterialModel; 7] = [
        MaterialModel::LinearElastic,
        MaterialModel::NeoHookean,
        MaterialModel::FixedCorotated,
        MaterialModel::Fluid,
        MaterialModel::VonMises,
        MaterialModel::DruckerPrager,
        MaterialModel::Snow,
    ];

    /// The variant stored as `code` (its `repr(u32)` value), if any: how a stored or C-side
    /// number becomes the enum without undefined behaviour.
    pub const fn from_code(code: u32) -> Option<MaterialModel> {
        match code {
            0 => Some(MaterialModel::LinearElastic),
            1 => Some(MaterialModel::NeoHookean),
            2 => Some(MaterialModel::FixedCorotated),
            3 => Some(MaterialModel::Fluid),
            4 => Some(MaterialModel::VonMises),
            5 => Some(MaterialModel::DruckerPrager),
            6 => Some(MaterialModel::Snow),
            _ => None,
        }
    }

    /// Whether the model keeps a plastic history per particle (and so needs
    /// [`crate::Effects::plasticity`]).
    pub const fn plastic(self) -> bool {
        matches!(
            self,
            MaterialModel::VonMises | MaterialModel::DruckerPrager | MaterialModel::Snow
        )
    }
}

/// How [`MaterialModel::DruckerPrager`]'s cone is fitted to Mohr-Coulomb's friction angle phi
/// (E40): the cone `|dev tau| + alpha tr tau <= 0` meets Mohr-Coulomb's pyramid where the fit
/// says. In plane strain the cone reads the two in-plane principal stresses alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum FrictionFit {
    /// Through the pyramid's compression corners (triaxial compression), `alpha = sqrt(2/3) 2
    /// sin(phi) / (3 - sin(phi))` (Klar et al. 2016): the default, as animation uses it. In
    /// plane strain its in-plane cone is wider than Mohr-Coulomb's: Rankine's coefficients at
    /// phi = 30 deg come out Ka 0.368 and Kp 2.717 (Mohr-Coulomb: 1/3 and 3).
    Compression = 0,
    /// Through the extension corners, `alpha = sqrt(2/3) 2 sin(phi) / (3 + sin(phi))`.
    Extension = 1,
    /// Inscribed in the pyramid, `alpha = sqrt(2) sin(phi) / sqrt(9 + 3 sin^2(phi))`.
    Inscribed = 2,
    /// Mohr-Coulomb exactly in plane strain: with the in-plane cone, `alpha = sin(phi) /
    /// sqrt(2)` gives `|s1 - s2| = -sin(phi) (s1 + s2)`, so Rankine's `Ka = (1 - sin phi) / (1
    /// + sin phi)` and `Kp = 1 / Ka`. In 3D and axisymmetric (three axes) it is the cone
    /// through `sqrt(J2) = sin(phi) |p|`, between the extension and inscribed fits.
    PlaneStrain = 3,
}

impl FrictionFit {
    /// The variant stored as `code`, if any.
    pub const fn from_code(code: u32) -> Option<FrictionFit> {
        match code {
            0 => Some(FrictionFit::Compression),
            1 => Some(FrictionFit::Extension),
            2 => Some(FrictionFit::Inscribed),
            3 => Some(FrictionFit::PlaneStrain),
            _ => None,
        }
    }

    /// The cone's `alpha` for the friction angle `phi`, radians.
    pub fn alpha(self, phi: f64) -> f64 {
        let s = libm::sin(phi);
        match self {
            FrictionFit::Compression => libm::sqrt(2.0 / 3.0) * 2.0 * s / (3.0 - s),
            FrictionFit::Extension => libm::sqrt(2.0 / 3.0) * 2.0 * s / (3.0 + s),
            FrictionFit::Inscribed => libm::sqrt(2.0) * s / libm::sqrt(9.0 + 3.0 * s * s),
            FrictionFit::PlaneStrain => s / libm::sqrt(2.0),
        }
    }
}

/// A material: model and isotropic elastic constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialDef {
    /// Constitutive model. Default: neo-Hookean, because it stays well posed at large strain.
    pub model: MaterialModel,
    /// Young's modulus E, Pa, > 0. Default 1 MPa: a soft rubber-like solid that a game scene can
    /// step with a stable time step near a millisecond on a 1 cm grid.
    pub youngs_modulus: Real,
    /// Poisson's ratio nu, in (-1, 0.5). Default 0.3, a typical solid.
    pub poisson_ratio: Real,
    /// Initial density rho_0, kg/m^3, > 0. Default 1000 (water-like).
    pub density: Real,
    /// Specific heat capacity C_p, J/(kg K), > 0 (used only with heat conduction). Default 1000,
    /// the order of most solids and of rubber.
    pub heat_capacity: Real,
    /// Thermal conductivity k, W/(m K), >= 0 (heat conduction only). Default 0: a material
    /// conducts only when its scene asks for it.
    pub conductivity: Real,
    /// Diffusivity D of the concentration potential, m^2/s, >= 0 (diffusion only). Default 0.
    pub diffusivity: Real,
    /// Linear thermal expansion coefficient alpha, 1/K, finite (heat conduction only): the
    /// material is free of stress under the isotropic stretch `1 + alpha (T - T_0)` per axis,
    /// `T` the grid temperature at the particle ([`crate::ParticlesView::grid_temperature`]).
    /// Default 0.
    pub thermal_expansion: Real,
    /// Stress-free temperature `T_0` of the thermal expansion, K, finite. Default 0.
    pub reference_temperature: Real,
    /// Linear swelling coefficient beta, strain per unit concentration potential, finite
    /// (diffusion only): the stress-free stretch gains `beta (c - c_0)` per axis, `c` the grid
    /// concentration at the particle. Default 0.
    pub swelling: Real,
    /// Stress-free concentration potential `c_0` of the swelling, finite. Default 0.
    pub reference_concentration: Real,
    /// Dynamic viscosity eta, Pa s, >= 0: the Newtonian stress `2 eta dev(sym grad v)` added
    /// to the model's (a fluid's viscosity; with a solid model, a Kelvin-Voigt damper).
    /// Default 0. Integrated explicitly: the step keeps `dt <= h^2 rho / (2 d (eta +
    /// zeta))`, with the bulk viscosity zeta.
    pub viscosity: Real,
    /// Bulk (volume) viscosity zeta, Pa s, >= 0: the stress `zeta tr(sym grad v) I` added to
    /// the model's (E46), which resists a change of volume at a rate and so damps sound: a
    /// fluid's acoustic modes, which its shear viscosity does not reach. Default 0.
    pub bulk_viscosity: Real,
    /// Rate k at which [`MaterialModel::Fluid`] relaxes a crowd, 1/s, >= 0 (E97): where its
    /// particles fill more than the space around them (the fill `phi > c = 1 + 1e-4`, from the
    /// particles' volumes `J V0` on the grid), `J <- J / (phi / c)^min(1, k dt)`, so that the
    /// pressure pushes them apart. Without it, particles packed by a collider's contact keep
    /// their `J` and a floating body sinks. Default 20/s; 0 turns it off (the step then does no such pass).
    /// Other models ignore it.
    pub volume_relaxation: Real,
    /// Bulk modulus K of [`MaterialModel::Fluid`], Pa, > 0 (other models take theirs from E
    /// and nu). Default 1e5 Pa: a sound speed of 10 m/s in a fluid of water's density, which
    /// keeps a 1 m deep tank within about 1 % of its volume under gravity (the usual weakly
    /// compressible choice: water's own 2.2 GPa would take a step 470 times shorter).
    pub bulk_modulus: Real,
    /// Exponent gamma of Tait's equation of state of [`MaterialModel::Fluid`], >= 1. Default 7,
    /// the value for water (Cole 1948; Monaghan's weakly compressible SPH).
    pub pressure_exponent: Real,
    /// Initial yield stress sigma_y of [`MaterialModel::VonMises`] in uniaxial tension, Pa,
    /// > 0. Default 1e4 Pa: yield at 1 % strain of the default E.
    pub yield_stress: Real,
    /// Linear isotropic hardening modulus H of [`MaterialModel::VonMises`], Pa, >= 0: the yield
    /// stress grows as `sigma_y + H eps_p` with the equivalent plastic strain. Default 0,
    /// perfectly plastic.
    pub hardening_modulus: Real,
    /// Friction angle phi of [`MaterialModel::DruckerPrager`], degrees, in [0, 90). Default 30,
    /// a typical dry sand.
    pub friction_angle: Real,
    /// How the Drucker-Prager cone is fitted to `friction_angle` ([`FrictionFit`]). Default
    /// [`FrictionFit::Compression`]; [`FrictionFit::PlaneStrain`] gives Mohr-Coulomb's (and
    /// Rankine's) earth pressures in plane strain.
    pub friction_fit: FrictionFit,
    /// Cohesion c of [`MaterialModel::DruckerPrager`], Pa, >= 0: the tension the material holds
    /// (its yield surface's apex is shifted by it). Default 0, dry sand.
    pub cohesion: Real,
    /// Critical compression theta_c of [`MaterialModel::Snow`], in (0, 1): singular values of
    /// `F_e` below `1 - theta_c` flow plastically. Default 0.025 (Stomakhin et al. 2013).
    pub critical_compression: Real,
    /// Critical stretch theta_s of [`MaterialModel::Snow`], > 0: singular values above
    /// `1 + theta_s` flow plastically. Default 0.0075 (Stomakhin et al. 2013).
    pub critical_stretch: Real,
    /// Hardening coefficient xi of [`MaterialModel::Snow`], in `[0, MAX_HARDENING_COEFFICIENT]`:
    /// the moduli scale by `exp(xi (1 - J_p))`. Default 10 (Stomakhin et al. 2013). The
    /// bound is the model's, not the step's: compaction raises the moduli at a fixed elastic
    /// strain, which puts energy into the material; at 100 blocks dropped at up to 30 m/s on
    /// a stick floor stay bounded, at 300 one dropped at 10 m/s gains kinetic energy without
    /// bound (the `ranges` test in `ffi/tests`).
    pub hardening_coefficient: Real,
}

impl MaterialDef {
    /// The documented defaults (see each field).
    pub const DEFAULT: MaterialDef = MaterialDef {
        model: MaterialModel::NeoHookean,
        youngs_modulus: 1.0e6,
        poisson_ratio: 0.3,
        density: 1000.0,
        heat_capacity: 1000.0,
        conductivity: 0.0,
        diffusivity: 0.0,
        thermal_expansion: 0.0,
        reference_temperature: 0.0,
        swelling: 0.0,
        reference_concentration: 0.0,
        viscosity: 0.0,
        bulk_viscosity: 0.0,
        volume_relaxation: 20.0,
        bulk_modulus: 1.0e5,
        pressure_exponent: 7.0,
        yield_stress: 1.0e4,
        hardening_modulus: 0.0,
        friction_angle: 30.0,
        friction_fit: FrictionFit::Compression,
        cohesion: 0.0,
        critical_compression: 0.025,
        critical_stretch: 0.0075,
        hardening_coefficient: 10.0,
    };

    /// Lamé constants (lambda, mu) for 3D and plane strain (E33); a fluid's are `(K, 0)`.
    pub fn lame(&self) -> (Real, Real) {
        if self.model == MaterialModel::Fluid {
            return (self.bulk_modulus, 0.0);
        }
        let e = self.youngs_modulus;
        let nu = self.poisson_ratio;
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        (lambda, mu)
    }

    /// Dilatational (P) wave speed `c = sqrt((K + 4G/3) / rho)` (E86), m/s: the speed the stable
    /// time step must resolve (a fluid's sound speed `sqrt(K / rho)`).
    pub fn wave_speed(&self) -> Real {
        let (lambda, mu) = self.lame();
        crate::math::sqrt((lambda + 2.0 * mu) / self.density)
    }

    /// Thermal diffusivity `k / (rho C_p)`, m^2/s: with [`MaterialDef::diffusivity`], what the
    /// explicit conduction step must resolve.
    pub fn thermal_diffusivity(&self) -> Real {
        self.conductivity / (self.density * self.heat_capacity)
    }
}

impl Default for MaterialDef {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Everything that fixes a world's size and method. Plain data; [`WorldDef::DEFAULT`] documents
/// each default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldDef {
    /// Dimension. Default [`Dimension::Plane2D`]: the cheapest, and what most game scenes need.
    pub dimension: Dimension,
    /// Position of the grid's lowest corner, m. Default the origin. Unused components (z in 2D)
    /// are ignored, even if not finite.
    pub origin: Vec3,
    /// Edge length h of the square (cubic) cells, m, > 0. Default 0.01 m: 1 cm resolves a
    /// 1 m scene with 100 cells per axis.
    pub cell_size: Real,
    /// Number of cells along x, y and z (z ignored in 2D), each >= 2 + 2 x the shape margin.
    /// Default 100 x 100 x 1: a 1 m square at the default cell size.
    pub cells: [u32; 3],
    /// Most particles the world can hold. Default 65536: a 1 m square block at 2 x 2 particles
    /// per 1 cm cell is 40000.
    pub particle_capacity: u32,
    /// Most materials the world can hold. Default 8.
    pub material_capacity: u32,
    /// Shape function. Default [`ShapeFunction::Gimp`] (uGIMP): it removes the cell-crossing
    /// noise of linear MPM for a small cost.
    pub shape: ShapeFunction,
    /// Particles per cell per axis `n`: sets the uGIMP particle half-width `l_p = h / (2 n)` and
    /// the spacing of the fill helpers. Default 2, the usual GIMP choice.
    pub particles_per_cell: u32,
    /// FLIP fraction beta in [0, 1] kept per substep (E22, E23): 1 is pure FLIP (no numerical
    /// damping), 0 is PIC. Default 0.99: a 1 % PIC blend removes the particle-grid velocity
    /// noise that pure FLIP keeps, at a damping rate `(1 - beta) / dt` on that noise only. That
    /// rate grows as the substep shrinks: for a flow that comes to rest, set 1 here and a
    /// [`WorldDef::pic_rate`] instead.
    pub flip_beta: Real,
    /// PIC share as a rate in time, 1/s, >= 0 and finite (E22): a substep of length `dt`
    /// blends with FLIP fraction `flip_beta exp(-pic_rate dt)`, so the particle velocity's
    /// departure from the grid's decays at `pic_rate` per second whatever the substep.
    /// Default 0 (the blend is `flip_beta`'s alone). With `flip_beta` 1 and 30/s, a sand
    /// column's run-out changes by 0.2 % from `E` 1e6 to 1e7 Pa and 1.8 % at half the Courant
    /// number, where `flip_beta` 0.99 gives 14 % and 8 % (10 cells across;
    /// `examples/collapse.rs`). It damps what the grid cannot carry, a rigid spin's edges
    /// too: keep it 0 where energy must last.
    pub pic_rate: Real,
    /// Velocity transfer. Default [`Transfer::Flip`]: no extra columns, and with
    /// [`WorldDef::flip_beta`] near 1 it keeps the most kinetic energy.
    pub transfer: Transfer,
    /// Where the stress update sits. Default [`UpdateOrder::Musl`]: it takes the velocity
    /// gradient from re-mapped momenta, which stays bounded when nodal masses are tiny.
    pub update_order: UpdateOrder,
    /// Gravity, m/s^2. Default (0, -9.81, 0): y is up. The z component is ignored in 2D.
    pub gravity: Vec3,
    /// Boundary condition of each face, indexed by [`Face`]. Default all [`Boundary::Slip`]:
    /// frictionless walls keep everything in the box and add no friction.
    pub faces: [Boundary; 6],
    /// Coulomb friction coefficient of each slip face, indexed by [`Face`], >= 0: where the
    /// material presses on the wall its speed along the wall (relative to the wall's
    /// `wall_velocity`) falls by `friction` times the normal speed the wall takes away
    /// (E94). Default 0: frictionless.
    pub wall_friction: [Real; 6],
    /// Velocity of each face's wall along its plane, m/s, indexed by [`Face`] (the component
    /// along the face's normal is not used: the wall stays where it is): a stick face moves
    /// the material on it at this velocity (a conveyor, a driven lid), a slip face's friction
    /// acts relative to it (E94). Default zero.
    pub wall_velocity: [Vec3; 6],
    /// Highest power of `grad v dt` kept in `dF = exp(grad v dt)` (E31), 1..=8.
    /// Default 2: second order, exact for the time integration's own order and cheap.
    pub exp_terms: u32,
    /// Courant number of the stable time step `dt = cfl h / (c_max + |v|_max)` (E88), in (0, 1];
    /// a step also keeps a collider near the material within `cfl` cells a substep.
    /// Default 0.5: the usual margin for explicit MPM with FLIP.
    pub cfl: Real,
    /// Most substeps one [`crate::World::step`] call may take, in `1..=`[`crate::MAX_SUBSTEPS`]:
    /// a `dt` that needs more is refused with [`crate::Error::SubstepLimit`] and changes
    /// nothing, so a call's cost is bounded by this times the particles' cost of a substep.
    /// Default 1000: a 60 Hz frame of a stiff solid at centimetre cells (steel on the default
    /// grid needs about 20,000 substeps) is refused at once instead of taking seconds; a host
    /// that wants such a frame raises the limit or steps with a smaller `dt`.
    pub max_substeps: u32,
    /// Runaway bound on the volume ratio `J = det F`, > 1: a particle whose `J` leaves
    /// `[1 / max_volume_ratio, max_volume_ratio]` in a step is frozen like one whose state
    /// turned non-finite, and counted in [`crate::StepReport::runaway`]. Default 100: no
    /// material the kernel models changes its volume a hundredfold, while an unstable scheme
    /// (linear shapes with USL) drives `J` past it long before stresses overflow. `INFINITY`
    /// removes the bound (inverted `F` still freezes).
    pub max_volume_ratio: Real,
    /// The most workers a host's task system may step the world on
    /// ([`crate::World::step_with_tasks`]), in `1..=`[`crate::MAX_WORKERS`]: the world's
    /// buffer holds the parallel step's scratch for that many (a few hundred bytes per
    /// worker; none for 1). Default 1: a host that steps on several cores says how many.
    /// The results do not depend on it, nor on the workers a step runs on. A world of fewer
    /// than [`crate::PARALLEL_FROM`] particles steps on the calling thread.
    pub workers: u32,
    /// The optional effects the scene uses. Default [`Effects::NONE`]: a scene pays only for
    /// what it declares.
    pub effects: Effects,
}

impl WorldDef {
    /// The documented defaults (see each field).
    pub const DEFAULT: WorldDef = WorldDef {
        dimension: Dimension::Plane2D,
        origin: Vec3::ZERO,
        cell_size: 0.01,
        cells: [100, 100, 1],
        particle_capacity: 65536,
        material_capacity: 8,
        shape: ShapeFunction::Gimp,
        particles_per_cell: 2,
        flip_beta: 0.99,
        pic_rate: 0.0,
        transfer: Transfer::Flip,
        update_order: UpdateOrder::Musl,
        gravity: Vec3::new(0.0, -9.81, 0.0),
        faces: [Boundary::Slip; 6],
        wall_friction: [0.0; 6],
        wall_velocity: [Vec3::ZERO; 6],
        exp_terms: 2,
        cfl: 0.5,
        max_substeps: 1000,
        max_volume_ratio: 100.0,
        workers: 1,
        effects: Effects::NONE,
    };

    /// The largest rates a world of this definition resolves in a step of at least
    /// [`MIN_STABLE_DT`] ([`Resolvable`]).
    pub fn resolvable(&self) -> Resolvable {
        let (h, cfl, floor) = (self.cell_size as f64, self.cfl as f64, MIN_STABLE_DT);
        Resolvable {
            speed: cfl * h / floor,
            rate: cfl / floor,
            diffusivity: cfl * h * h / (2.0 * self.axes() as f64 * floor),
        }
    }

    /// Number of spatial axes (2 or 3).
    pub const fn axes(&self) -> usize {
        match self.dimension {
            Dimension::ThreeD => 3,
            _ => 2,
        }
    }
}

/// The largest [`WorldDef::max_substeps`] a definition may set.
pub const MAX_SUBSTEPS: u32 = 1 << 20;

/// The largest [`WorldDef::workers`] a definition may set.
pub const MAX_WORKERS: u32 = 256;

/// The fewest particles [`crate::World::step_with_tasks`] hands a host's task system: below it
/// the step runs on the calling thread, where sharing the passes costs more than a second
/// worker saves (`step_cost --threads 2` against 1: 1.23 times as long at 2,048
/// particles in 2D, 1.25 at 512 in 3D; 0.64 at 4,096 in 3D, 0.68 at 8,192 in 2D).
pub const PARALLEL_FROM: usize = 4096;

/// The largest [`MaterialDef::hardening_coefficient`] snow may have (see there why).
pub const MAX_HARDENING_COEFFICIENT: Real = 100.0;

/// The shortest stable time step a world accepts, s: 1e-15 (a femtosecond, below the period
/// of any molecular vibration, where a continuum model no longer describes matter). A
/// material, a damping rate or a state whose own stable step would be shorter is refused
/// ([`crate::Error::StableStepTooShort`] when added, [`crate::Error::InvalidState`] when a
/// snapshot opens), so that [`crate::World::stable_dt`] is a step the kernel integrates, never
/// a floor it was clamped to. See [`WorldDef::resolvable`].
pub const MIN_STABLE_DT: f64 = 1.0e-15;

/// What a world resolves in a stable step of at least [`MIN_STABLE_DT`] (`cfl` its Courant
/// number, `h` its cell size, `d` its axes), each the bound of one term of the stable step
/// ([`crate::World::stable_dt`]):
/// - a material's wave speed (snow's as hardened), m/s: `cfl h / MIN_STABLE_DT`;
/// - the damping rates of the definition, summed (grid, particle, zones; the thermostat's
///   alpha adapts to the step), 1/s: `cfl / MIN_STABLE_DT`; each per-particle rate at most
///   half of what that sum leaves, so that no particle sees more;
/// - a material's thermal diffusivity, diffusivity or kinematic viscosity (each where it
///   acts), m^2/s: `cfl h^2 / (2 d MIN_STABLE_DT)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolvable {
    /// Largest wave speed, m/s.
    pub speed: f64,
    /// Largest sum of damping rates, 1/s.
    pub rate: f64,
    /// Largest diffusivity, m^2/s.
    pub diffusivity: f64,
}

impl Default for WorldDef {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `from_code` inverts `as u32` for every variant and answers `None` for every other code
    /// up to 1023 and at the top of the range.
    #[test]
    fn from_code_inverts_the_stored_number() {
        fn check<T: Copy + PartialEq + core::fmt::Debug>(
            all: &[T],
            number: fn(T) -> u32,
            from: fn(u32) -> Option<T>,
        ) {
            for &v in all {
                assert_eq!(from(number(v)), Some(v));
            }
            let known = |c: u32| all.iter().any(|&v| number(v) == c);
            for c in (0..1024).chain([u32::MAX - 1, u32::MAX]) {
                assert_eq!(from(c).is_some(), known(c), "code {c}");
            }
        }
        use Dimension as Dm;
        check(
            &[Dm::Plane2D, Dm::ThreeD, Dm::Axisymmetric2D],
            |v| v as u32,
            Dm::from_code,
        );
        use ShapeFunction as Sf;
        let shapes = [
            Sf::Linear,
            Sf::Gimp,
            Sf::QuadraticBspline,
            Sf::CubicBspline,
            Sf::CpGimp,
        ];
        check(&shapes, |v| v as u32, Sf::from_code);
        use UpdateOrder as Uo;
        check(&[Uo::Usf, Uo::Usl, Uo::Musl], |v| v as u32, Uo::from_code);
        use Face as F;
        let faces = [F::XMin, F::XMax, F::YMin, F::YMax, F::ZMin, F::ZMax];
        check(&faces, |v| v as u32, F::from_code);
        use Boundary as Bd;
        check(
            &[Bd::Stick, Bd::Slip, Bd::Open, Bd::Periodic],
            |v| v as u32,
            Bd::from_code,
        );
        use Transfer as Tr;
        check(
            &[
                Tr::Flip,
                Tr::Apic,
                Tr::FlipParticleVelocity,
                Tr::Mls,
                Tr::FlipMomentum,
                // Every order a code below 1024 holds (the validation refuses 0).
                Tr::Xpic(0),
                Tr::Xpic(1),
                Tr::Xpic(2),
                Tr::Xpic(3),
                Tr::Fmpm(0),
                Tr::Fmpm(1),
                Tr::Fmpm(2),
                Tr::Fmpm(3),
            ],
            |v| v.code(),
            Tr::from_code,
        );
        use MaterialModel as Mm;
        check(&Mm::ALL, |v| v as u32, Mm::from_code);
    }
}
